// libFuzzer target for the CSG expression parser (render/csg/csg_tree.h): any string either parses into a
// tree that normalises and prints, or is refused with std::invalid_argument; nothing else.
#include <cstdint>
#include <map>
#include <stdexcept>
#include <string>

#include "relaxed_connectivity/render/csg/csg_tree.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  const std::string expression(reinterpret_cast<const char*>(data), size);
  static const std::map<std::string, int> names = {{"a", 0}, {"b", 1}, {"sphere", 2}};
  try {
    const rc::CsgTree tree = rc::CsgTree::parse(expression, names);
    (void)tree.toString();
  } catch (const std::invalid_argument&) {
  }
  return 0;
}
