// CSG tree over surface patches (thesis 4.1, 4.3): union, intersection, difference and complement; a parser
// for expressions such as "A - (B | C)"; normalisation to union/intersection nodes with inverted leaves
// (4.3); the inside test of Algorithm 4.3 and the fragment test of Algorithm 4.2 in three-valued logic
// (4.9)/(4.10).
#pragma once

#include <map>
#include <string>
#include <vector>

#include "relaxed_connectivity/render/csg/csg_tri_logic.h"

namespace rc {

class CsgTree {
 public:
  enum class Op : uint8_t { kLeaf, kUnion, kIntersection, kDifference, kComplement };
  struct Node {
    Op op = Op::kLeaf;
    int patch = -1;         ///< leaves: patch id
    bool inverted = false;  ///< leaves: complemented patch (normalised trees, 4.3)
    int left = -1;          ///< first child (the only child of a complement)
    int right = -1;         ///< second child of a binary node
    int parent = -1;
  };

  /// Parses an expression. Operators: '!' complement (tightest), '&' intersection, then '|' union and '-'
  /// difference (same level, left-associative), parentheses. Operands are names looked up in `names`
  /// (name -> patch id) or non-negative integers taken as patch ids. A patch may appear only once (Algorithm
  /// 4.2 starts at "the" leaf of the fragment's patch). Throws std::invalid_argument with the 1-based column.
  static CsgTree parse(const std::string& expression, const std::map<std::string, int>& names = {});

  /// Programmatic construction.
  static CsgTree leaf(int patch, const std::string& name = "");
  static CsgTree unite(const CsgTree& a, const CsgTree& b);
  static CsgTree intersect(const CsgTree& a, const CsgTree& b);
  static CsgTree subtract(const CsgTree& a, const CsgTree& b);
  static CsgTree complement(const CsgTree& a);

  /// Rewrites A - B as A & !B and pushes complements to the leaves by De Morgan (4.3): the result has only
  /// union/intersection nodes and leaves with an `inverted` flag.
  CsgTree normalized() const;
  bool isNormalized() const;
  /// True if the normalised tree has a complemented leaf (the expression has a difference or complement).
  bool hasComplementedPatches() const;

  /// Infix form with names where known ("A & (!B & !C)"); every nested binary node is parenthesised.
  std::string toString() const;

  bool empty() const { return nodes_.empty(); }
  int root() const { return root_; }
  const Node& node(int i) const { return nodes_[i]; }
  const std::vector<Node>& nodes() const { return nodes_; }
  /// Leaf node of `patch`, -1 if the patch is not in the tree.
  int leafOf(int patch) const;
  /// Patch ids of all leaves, ascending.
  std::vector<int> patches() const;
  const std::map<int, std::string>& names() const { return names_; }

  /// Algorithm 4.3 with unknowns (4.9)/(4.10) on a normalised tree: is x inside the object of `node`?
  /// `insidePatch(patch)` returns the (non-inverted) classification of x against a patch (Algorithm 4.4).
  template <class InsidePatch>
  Tri insideTree(int node, InsidePatch&& insidePatch) const {
    const Node& n = nodes_[node];
    if (n.op == Op::kLeaf) {
      const Tri in = insidePatch(n.patch);
      return n.inverted ? triNot(in) : in;
    }
    const Tri a = insideTree(n.left, insidePatch);
    const Tri b = insideTree(n.right, insidePatch);
    return n.op == Op::kIntersection ? triAnd(a, b) : triOr(a, b);  // (4.8) / (4.7)
  }

  /// Algorithm 4.2 on a normalised tree: is a point x on the surface of `patch` also on the surface of the
  /// root object? Walks up from the patch's leaf; at each level the sibling's classification decides with
  /// (4.5) (intersection: on = in) or (4.6) (union: on = !in); unknown leaves `on` unchanged. An inverted own
  /// leaf changes nothing here: the surface of !C is the surface of C. Throws if the patch is not in the
  /// tree.
  template <class InsidePatch>
  bool fragmentOnSurface(int patch, InsidePatch&& insidePatch) const {
    int a = leafOfChecked(patch);
    bool on = true;
    while (on && nodes_[a].parent >= 0) {
      const Node& father = nodes_[nodes_[a].parent];
      const int sibling = father.left == a ? father.right : father.left;
      const Tri in = insideTree(sibling, insidePatch);
      if (in != Tri::kUnknown) on = father.op == Op::kIntersection ? in == Tri::kTrue : in == Tri::kFalse;
      a = nodes_[a].parent;
    }
    return on;
  }

 private:
  int leafOfChecked(int patch) const;
  int addNode(const Node& n);
  int copyFrom(const CsgTree& other, int node);
  static CsgTree binary(Op op, const CsgTree& a, const CsgTree& b);
  int normalizeInto(CsgTree& out, int node, bool negate) const;
  void appendString(int node, bool top, std::string& s) const;
  void indexLeaves();

  std::vector<Node> nodes_;
  int root_ = -1;
  std::map<int, std::string> names_;          // patch id -> name, for printing
  std::vector<std::pair<int, int>> leaf_of_;  // (patch, leaf node), sorted by patch
};

}  // namespace rc
