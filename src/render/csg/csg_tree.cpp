#include "relaxed_connectivity/render/csg/csg_tree.h"

#include <algorithm>
#include <cctype>
#include <stdexcept>

namespace rc {

namespace {

// Recursive-descent parser: expr := term (('|' | '-') term)*, term := factor ('&' factor)*,
// factor := '!' factor | '(' expr ')' | operand.
class Parser {
 public:
  Parser(const std::string& text, const std::map<std::string, int>& names) : text_(text), names_(names) {}

  CsgTree parseAll() {
    skipSpace();
    if (pos_ >= text_.size()) fail(pos_, "empty expression");
    CsgTree tree = parseExpr();
    skipSpace();
    if (pos_ < text_.size()) {
      if (text_[pos_] == ')') fail(pos_, "unmatched ')'");
      fail(pos_, std::string("expected an operator (|, &, -) but found '") + text_[pos_] + "'");
    }
    return tree;
  }

 private:
  [[noreturn]] void fail(size_t pos, const std::string& what) const {
    throw std::invalid_argument("CSG expression \"" + text_ + "\": column " + std::to_string(pos + 1) + ": " +
                                what);
  }
  void skipSpace() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skipSpace();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }

  CsgTree parseExpr() {
    CsgTree left = parseTerm();
    for (;;) {
      if (accept('|')) {
        left = CsgTree::unite(left, parseTerm());
      } else if (accept('-')) {
        left = CsgTree::subtract(left, parseTerm());
      } else {
        return left;
      }
    }
  }
  CsgTree parseTerm() {
    CsgTree left = parseFactor();
    while (accept('&')) left = CsgTree::intersect(left, parseFactor());
    return left;
  }
  CsgTree parseFactor() {
    skipSpace();
    if (pos_ >= text_.size()) fail(pos_, "unexpected end, expected a patch name, '!' or '('");
    const char c = text_[pos_];
    // (found by fuzz_csg_expression: thousands of nested '(' or '!' overflowed the stack)
    constexpr int kMaxNesting = 256;
    if ((c == '!' || c == '(') && depth_ >= kMaxNesting)
      fail(pos_, "nested deeper than " + std::to_string(kMaxNesting) + " levels");
    const Nesting nesting(&depth_);
    if (c == '!') {
      ++pos_;
      return CsgTree::complement(parseFactor());
    }
    if (c == '(') {
      const size_t open = pos_++;
      skipSpace();
      if (pos_ < text_.size() && text_[pos_] == ')') fail(pos_, "empty parentheses");
      CsgTree inner = parseExpr();
      if (!accept(')')) {
        skipSpace();
        if (pos_ >= text_.size()) fail(open, "'(' is never closed");
        fail(pos_, std::string("expected ')' but found '") + text_[pos_] + "'");
      }
      return inner;
    }
    return parseOperand();
  }
  CsgTree parseOperand() {
    const size_t start = pos_;
    auto is_name_char = [](char ch) {
      return std::isalnum(static_cast<unsigned char>(ch)) || ch == '_' || ch == '.';
    };
    while (pos_ < text_.size() && is_name_char(text_[pos_])) ++pos_;
    if (pos_ == start)
      fail(start, std::string("expected a patch name, '!' or '(' but found '") + text_[start] + "'");
    const std::string name = text_.substr(start, pos_ - start);
    int patch = -1;
    auto it = names_.find(name);
    if (it != names_.end()) {
      patch = it->second;
    } else if (std::all_of(name.begin(), name.end(),
                           [](char ch) { return std::isdigit(static_cast<unsigned char>(ch)); })) {
      if (name.size() > 9) fail(start, "patch id '" + name + "' is too large");
      patch = std::stoi(name);
    } else {
      fail(start, "unknown patch name '" + name + "'");
    }
    if (std::find(used_.begin(), used_.end(), patch) != used_.end())
      fail(start, "patch '" + name + "' (id " + std::to_string(patch) + ") appears more than once");
    used_.push_back(patch);
    return CsgTree::leaf(patch, it != names_.end() ? name : std::string());
  }

  /// Counts one level of '!' or '(' while a factor is parsed.
  struct Nesting {
    explicit Nesting(int* depth) : depth_(depth) { ++*depth_; }
    ~Nesting() { --*depth_; }
    Nesting(const Nesting&) = delete;
    Nesting& operator=(const Nesting&) = delete;
    int* depth_;
  };

  const std::string& text_;
  const std::map<std::string, int>& names_;
  size_t pos_ = 0;
  int depth_ = 0;
  std::vector<int> used_;
};

}  // namespace

CsgTree CsgTree::parse(const std::string& expression, const std::map<std::string, int>& names) {
  return Parser(expression, names).parseAll();
}

int CsgTree::addNode(const Node& n) {
  nodes_.push_back(n);
  return static_cast<int>(nodes_.size()) - 1;
}

CsgTree CsgTree::leaf(int patch, const std::string& name) {
  if (patch < 0)
    throw std::invalid_argument("CsgTree::leaf: patch id " + std::to_string(patch) + " is negative");
  CsgTree t;
  Node n;
  n.patch = patch;
  t.root_ = t.addNode(n);
  if (!name.empty()) t.names_[patch] = name;
  t.indexLeaves();
  return t;
}

int CsgTree::copyFrom(const CsgTree& other, int node) {
  Node n = other.nodes_[node];
  const int left = n.left >= 0 ? copyFrom(other, n.left) : -1;
  const int right = n.right >= 0 ? copyFrom(other, n.right) : -1;
  n.left = left;
  n.right = right;
  n.parent = -1;
  const int id = addNode(n);
  if (left >= 0) nodes_[left].parent = id;
  if (right >= 0) nodes_[right].parent = id;
  return id;
}

CsgTree CsgTree::binary(Op op, const CsgTree& a, const CsgTree& b) {
  if (a.empty() || b.empty()) throw std::invalid_argument("CsgTree: operand of a binary operator is empty");
  for (int p : b.patches())
    if (a.leafOf(p) >= 0)
      throw std::invalid_argument("CsgTree: patch " + std::to_string(p) + " appears in both operands");
  CsgTree t;
  Node n;
  n.op = op;
  n.left = t.copyFrom(a, a.root_);
  n.right = t.copyFrom(b, b.root_);
  t.root_ = t.addNode(n);
  t.nodes_[n.left].parent = t.root_;
  t.nodes_[n.right].parent = t.root_;
  t.names_ = a.names_;
  t.names_.insert(b.names_.begin(), b.names_.end());
  t.indexLeaves();
  return t;
}

CsgTree CsgTree::unite(const CsgTree& a, const CsgTree& b) {
  return binary(Op::kUnion, a, b);
}
CsgTree CsgTree::intersect(const CsgTree& a, const CsgTree& b) {
  return binary(Op::kIntersection, a, b);
}
CsgTree CsgTree::subtract(const CsgTree& a, const CsgTree& b) {
  return binary(Op::kDifference, a, b);
}

CsgTree CsgTree::complement(const CsgTree& a) {
  if (a.empty()) throw std::invalid_argument("CsgTree: operand of a complement is empty");
  CsgTree t;
  Node n;
  n.op = Op::kComplement;
  n.left = t.copyFrom(a, a.root_);
  t.root_ = t.addNode(n);
  t.nodes_[n.left].parent = t.root_;
  t.names_ = a.names_;
  t.indexLeaves();
  return t;
}

int CsgTree::normalizeInto(CsgTree& out, int node, bool negate) const {
  const Node& n = nodes_[node];
  Node m;
  switch (n.op) {
    case Op::kLeaf:
      m.patch = n.patch;
      m.inverted = n.inverted != negate;
      return out.addNode(m);
    case Op::kComplement:
      return normalizeInto(out, n.left, !negate);  // !!A = A
    case Op::kUnion:                               // !(A | B) = !A & !B
    case Op::kIntersection:                        // !(A & B) = !A | !B
      m.op = (n.op == Op::kUnion) != negate ? Op::kUnion : Op::kIntersection;
      m.left = normalizeInto(out, n.left, negate);
      m.right = normalizeInto(out, n.right, negate);
      break;
    case Op::kDifference:  // A - B = A & !B; !(A & !B) = !A | B
      m.op = negate ? Op::kUnion : Op::kIntersection;
      m.left = normalizeInto(out, n.left, negate);
      m.right = normalizeInto(out, n.right, !negate);
      break;
  }
  const int id = out.addNode(m);
  out.nodes_[m.left].parent = id;
  out.nodes_[m.right].parent = id;
  return id;
}

CsgTree CsgTree::normalized() const {
  CsgTree out;
  if (empty()) return out;
  out.root_ = normalizeInto(out, root_, false);
  out.names_ = names_;
  out.indexLeaves();
  return out;
}

bool CsgTree::hasComplementedPatches() const {
  const CsgTree normal = isNormalized() ? *this : normalized();
  for (const Node& n : normal.nodes())
    if (n.op == Op::kLeaf && n.inverted) return true;
  return false;
}

bool CsgTree::isNormalized() const {
  for (const Node& n : nodes_)
    if (n.op != Op::kLeaf && n.op != Op::kUnion && n.op != Op::kIntersection) return false;
  return !empty();
}

void CsgTree::appendString(int node, bool top, std::string& s) const {
  const Node& n = nodes_[node];
  if (n.op == Op::kLeaf) {
    if (n.inverted) s += '!';
    auto it = names_.find(n.patch);
    s += it != names_.end() ? it->second : std::to_string(n.patch);
    return;
  }
  if (n.op == Op::kComplement) {
    s += '!';
    appendString(n.left, nodes_[n.left].op == Op::kLeaf || nodes_[n.left].op == Op::kComplement, s);
    return;
  }
  if (!top) s += '(';
  appendString(n.left, false, s);
  s += n.op == Op::kUnion ? " | " : (n.op == Op::kIntersection ? " & " : " - ");
  appendString(n.right, false, s);
  if (!top) s += ')';
}

std::string CsgTree::toString() const {
  std::string s;
  if (!empty()) appendString(root_, true, s);
  return s;
}

void CsgTree::indexLeaves() {
  leaf_of_.clear();
  for (int i = 0; i < static_cast<int>(nodes_.size()); ++i)
    if (nodes_[i].op == Op::kLeaf) leaf_of_.emplace_back(nodes_[i].patch, i);
  std::sort(leaf_of_.begin(), leaf_of_.end());
}

int CsgTree::leafOf(int patch) const {
  auto it = std::lower_bound(leaf_of_.begin(), leaf_of_.end(), std::make_pair(patch, -1));
  return it != leaf_of_.end() && it->first == patch ? it->second : -1;
}

int CsgTree::leafOfChecked(int patch) const {
  const int leaf = leafOf(patch);
  if (leaf < 0)
    throw std::invalid_argument("CsgTree: patch " + std::to_string(patch) + " is not in the tree");
  return leaf;
}

std::vector<int> CsgTree::patches() const {
  std::vector<int> out;
  for (const auto& pl : leaf_of_) out.push_back(pl.first);
  return out;
}

}  // namespace rc
