// CSG tree: parser, normalisation (4.3), printer, three-valued logic (4.9)/(4.10), Algorithms 4.2 and 4.3.
#include <gtest/gtest.h>

#include <map>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/render/csg/csg_tree.h"

namespace rc {
namespace {

const std::map<std::string, int> kNames = {{"A", 0}, {"B", 1}, {"C", 2}, {"D", 3}};

std::string normalizedString(const std::string& expr) {
  return CsgTree::parse(expr, kNames).normalized().toString();
}

// The error message of parsing `expr`, or "" if it parses.
std::string parseError(const std::string& expr) {
  try {
    CsgTree::parse(expr, kNames);
  } catch (const std::invalid_argument& e) {
    return e.what();
  }
  return "";
}

TEST(CsgTreeParse, PrintsParsedExpressions) {
  EXPECT_EQ(CsgTree::parse("A - (B | C)", kNames).toString(), "A - (B | C)");
  EXPECT_EQ(CsgTree::parse("A&!B", kNames).toString(), "A & !B");
  EXPECT_EQ(CsgTree::parse("(0 | 1) & 2").toString(), "(0 | 1) & 2");
  EXPECT_EQ(CsgTree::parse("!(A | B)", kNames).toString(), "!(A | B)");
}

TEST(CsgTreeParse, PrecedenceAndAssociativity) {
  EXPECT_EQ(CsgTree::parse("A | B & C", kNames).toString(), "A | (B & C)");
  EXPECT_EQ(CsgTree::parse("A & B | C", kNames).toString(), "(A & B) | C");
  EXPECT_EQ(CsgTree::parse("A - B - C", kNames).toString(), "(A - B) - C");
  EXPECT_EQ(CsgTree::parse("A - B | C", kNames).toString(), "(A - B) | C");
  EXPECT_EQ(CsgTree::parse("!A & B", kNames).toString(), "!A & B");
}

TEST(CsgTreeParse, NumbersAndNamesMapToPatchIds) {
  const CsgTree t = CsgTree::parse("(0 | 1) & 2");
  EXPECT_EQ(t.patches(), (std::vector<int>{0, 1, 2}));
  const CsgTree u = CsgTree::parse("C - (A | 7)", kNames);
  EXPECT_EQ(u.patches(), (std::vector<int>{0, 2, 7}));
  EXPECT_GE(u.leafOf(7), 0);
  EXPECT_EQ(u.leafOf(1), -1);
  EXPECT_EQ(u.node(u.leafOf(2)).patch, 2);
}

TEST(CsgTreeNormalize, DifferenceOfUnionAsInTheThesis) {
  // 4.3: A \ (B u C) -> A n !(B u C) -> A n (!B n !C)
  const CsgTree n = CsgTree::parse("A - (B | C)", kNames).normalized();
  EXPECT_EQ(n.toString(), "A & (!B & !C)");
  EXPECT_TRUE(n.isNormalized());
  EXPECT_FALSE(CsgTree::parse("A - (B | C)", kNames).isNormalized());
  EXPECT_FALSE(n.node(n.leafOf(0)).inverted);
  EXPECT_TRUE(n.node(n.leafOf(1)).inverted);
  EXPECT_TRUE(n.node(n.leafOf(2)).inverted);
}

TEST(CsgTreeNormalize, ComplementsArePushedToLeaves) {
  EXPECT_EQ(normalizedString("A & !B"), "A & !B");
  EXPECT_EQ(normalizedString("!!A"), "A");
  EXPECT_EQ(normalizedString("!!!A"), "!A");
  EXPECT_EQ(normalizedString("!(!A | B)"), "A & !B");
  EXPECT_EQ(normalizedString("!(A - B)"), "!A | B");
  EXPECT_EQ(normalizedString("!!(A - !B)"), "A & B");
  EXPECT_EQ(normalizedString("!((A & B) | !(C - D))"), "(!A | !B) & (C & !D)");
  EXPECT_EQ(normalizedString("(0 | 1) & 2"), "(0 | 1) & 2");
  for (const char* e : {"!(A | (B & !(C - D)))", "A - B - C - D", "!A"})
    EXPECT_TRUE(CsgTree::parse(e, kNames).normalized().isNormalized()) << e;
}

TEST(CsgTreeParse, ErrorsNameTheColumn) {
  EXPECT_NE(parseError("A - (B | C").find("column 5: '(' is never closed"), std::string::npos)
      << parseError("A - (B | C");
  EXPECT_NE(parseError("A + B").find("column 3"), std::string::npos) << parseError("A + B");
  EXPECT_NE(parseError("A & E").find("column 5: unknown patch name 'E'"), std::string::npos)
      << parseError("A & E");
  EXPECT_NE(parseError("A B").find("column 3"), std::string::npos);
  EXPECT_NE(parseError("()").find("column 2: empty parentheses"), std::string::npos);
  EXPECT_NE(parseError("A & ").find("column 5: unexpected end"), std::string::npos) << parseError("A & ");
  EXPECT_NE(parseError("  ").find("empty expression"), std::string::npos);
  EXPECT_NE(parseError("A | B)").find("column 6: unmatched ')'"), std::string::npos);
  EXPECT_NE(parseError("A | !A").find("column 6"), std::string::npos) << parseError("A | !A");
  EXPECT_NE(parseError("A & (B | C) & (D | B)").find("column 20"), std::string::npos);
  EXPECT_NE(parseError("A - | B").find("column 5"), std::string::npos);
  EXPECT_EQ(parseError("A & B"), "");
  // Nesting is bounded (fuzz_csg_expression overflowed the stack with thousands of '(' or '!').
  EXPECT_EQ(parseError(std::string(256, '(') + "A" + std::string(256, ')')), "");
  EXPECT_NE(parseError(std::string(257, '(') + "A" + std::string(257, ')'))
                .find("column 257: nested deeper than 256"),
            std::string::npos);
  EXPECT_NE(parseError(std::string(100000, '!') + "A").find("nested deeper than 256"), std::string::npos);
}

TEST(TriLogic, ExtendedAndOrTablesAreExhaustivelyCorrect) {
  const Tri T = Tri::kTrue, F = Tri::kFalse, U = Tri::kUnknown;
  const Tri all[3] = {F, T, U};
  // (4.9)/(4.10): b op unknown = b for every b; otherwise Boolean.
  const Tri and_table[3][3] = {{F, F, F}, {F, T, T}, {F, T, U}};
  const Tri or_table[3][3] = {{F, T, F}, {T, T, T}, {F, T, U}};
  for (int a = 0; a < 3; ++a)
    for (int b = 0; b < 3; ++b) {
      EXPECT_EQ(triAnd(all[a], all[b]), and_table[a][b]) << triName(all[a]) << " and " << triName(all[b]);
      EXPECT_EQ(triOr(all[a], all[b]), or_table[a][b]) << triName(all[a]) << " or " << triName(all[b]);
      EXPECT_EQ(triAnd(all[a], all[b]), triAnd(all[b], all[a]));
      EXPECT_EQ(triOr(all[a], all[b]), triOr(all[b], all[a]));
    }
  EXPECT_EQ(triNot(T), F);
  EXPECT_EQ(triNot(F), T);
  EXPECT_EQ(triNot(U), U);
}

// insidePatch given as a table over patches 0..3.
struct TableInside {
  Tri value[4];
  Tri operator()(int patch) const { return value[patch]; }
};

TEST(CsgTreeAlgorithms, InsideTreeFollowsAlgorithm43WithUnknowns) {
  const Tri T = Tri::kTrue, F = Tri::kFalse, U = Tri::kUnknown;
  const CsgTree t = CsgTree::parse("(A & B) | !C", kNames).normalized();
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{T, T, T, U}}), T);
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{T, F, T, U}}), F);
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{T, F, F, U}}), T);  // !C
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{U, F, T, U}}), F);  // unknown & false = false
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{U, U, T, U}}), F);  // (unknown) | !true = false
  EXPECT_EQ(t.insideTree(t.root(), TableInside{{U, U, U, U}}), U);
}

TEST(CsgTreeAlgorithms, FragmentTestOfFigure45Tree) {
  // (A & B) & C, fragment of C: on = [inside A & B] with unknowns dropped (Fig. 4.5).
  const Tri T = Tri::kTrue, F = Tri::kFalse, U = Tri::kUnknown;
  const CsgTree t = CsgTree::parse("(A & B) & C", kNames).normalized();
  EXPECT_TRUE(t.fragmentOnSurface(2, TableInside{{T, T, U, U}}));
  EXPECT_FALSE(t.fragmentOnSurface(2, TableInside{{T, F, U, U}}));
  EXPECT_TRUE(t.fragmentOnSurface(2, TableInside{{T, U, U, U}}));  // s2: B unknown -> only A decides
  EXPECT_FALSE(t.fragmentOnSurface(2, TableInside{{F, U, U, U}}));
  EXPECT_TRUE(t.fragmentOnSurface(2, TableInside{{U, U, U, U}}));  // unknown never discards
  // Fragment of A: sibling B first, then C.
  EXPECT_TRUE(t.fragmentOnSurface(0, TableInside{{U, T, T, U}}));
  EXPECT_FALSE(t.fragmentOnSurface(0, TableInside{{U, T, F, U}}));
  EXPECT_FALSE(t.fragmentOnSurface(0, TableInside{{U, F, U, U}}));
}

TEST(CsgTreeAlgorithms, DifferenceAndUnionFollowEquations45And46) {
  const Tri T = Tri::kTrue, F = Tri::kFalse, U = Tri::kUnknown;
  const CsgTree diff = CsgTree::parse("A - B", kNames).normalized();   // A & !B
  EXPECT_FALSE(diff.fragmentOnSurface(0, TableInside{{U, T, U, U}}));  // A inside B: removed
  EXPECT_TRUE(diff.fragmentOnSurface(0, TableInside{{U, F, U, U}}));
  // B's own leaf is inverted: its surface is unchanged, kept where inside A (4.5).
  EXPECT_TRUE(diff.fragmentOnSurface(1, TableInside{{T, U, U, U}}));
  EXPECT_FALSE(diff.fragmentOnSurface(1, TableInside{{F, U, U, U}}));
  const CsgTree uni = CsgTree::parse("A | B", kNames).normalized();  // (4.6)
  EXPECT_FALSE(uni.fragmentOnSurface(0, TableInside{{U, T, U, U}}));
  EXPECT_TRUE(uni.fragmentOnSurface(0, TableInside{{U, F, U, U}}));
  EXPECT_TRUE(uni.fragmentOnSurface(0, TableInside{{U, U, U, U}}));
  const CsgTree single = CsgTree::parse("!A", kNames).normalized();
  EXPECT_TRUE(single.fragmentOnSurface(0, TableInside{{F, F, F, F}}));
  EXPECT_THROW(single.fragmentOnSurface(3, TableInside{{F, F, F, F}}), std::invalid_argument);
}

TEST(CsgTreeAlgorithms, BottomUpTestMatchesAppendixAOnAllAssignments) {
  // Algorithm 4.2 vs Algorithm A.1 (no early exit) on every true/false/unknown assignment of a 4-patch tree.
  const CsgTree t =
      CsgTree::parse("(A - (B | !C)) | (D & !A2)", {{"A", 0}, {"B", 1}, {"C", 2}, {"D", 3}, {"A2", 4}})
          .normalized();
  int checked = 0;
  for (int code = 0; code < 243; ++code) {
    Tri v[5];
    for (int p = 0, c = code; p < 5; ++p, c /= 3) v[p] = static_cast<Tri>(c % 3);
    auto inside = [&](int patch) { return v[patch]; };
    for (int own = 0; own < 5; ++own) {
      bool on = true;  // Algorithm A.1
      for (int a = t.leafOf(own); t.node(a).parent >= 0; a = t.node(a).parent) {
        const CsgTree::Node& f = t.node(t.node(a).parent);
        const Tri in = t.insideTree(f.left == a ? f.right : f.left, inside);
        if (in != Tri::kUnknown)
          on = on && (f.op == CsgTree::Op::kIntersection ? in == Tri::kTrue : in == Tri::kFalse);
      }
      EXPECT_EQ(t.fragmentOnSurface(own, inside), on);
      ++checked;
    }
  }
  EXPECT_EQ(checked, 243 * 5);
}

}  // namespace
}  // namespace rc
