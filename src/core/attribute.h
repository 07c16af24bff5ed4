// Named, typed per-surfel attribute columns (paint state, patch id, unknown PointCloud2/PLY fields, ...).
#pragma once

#include <cstdint>
#include <cstring>
#include <deque>
#include <stdexcept>
#include <string>
#include <vector>

namespace rc {

/// Scalar types of an attribute; the same set as sensor_msgs/PointField and PLY properties.
enum class ScalarType : uint8_t { kInt8, kUInt8, kInt16, kUInt16, kInt32, kUInt32, kFloat32, kFloat64 };

size_t scalarSize(ScalarType type);
const char* scalarName(ScalarType type);
/// The scalar of `type` at `p` (host byte order, any alignment) as a double.
double scalarToDouble(const uint8_t* p, ScalarType type);
/// Writes `value` converted to `type` at `out` (host byte order, any alignment).
void doubleToScalar(double value, ScalarType type, uint8_t* out);

/// One attribute column: `count` scalars of `type` per surfel, stored as raw bytes (so any field survives a
/// round trip bit-exactly, whether or not this library understands it).
struct Attribute {
  std::string name;
  ScalarType type = ScalarType::kFloat32;
  uint32_t count = 1;
  std::vector<uint8_t> bytes;  ///< size() == elementCount * count * scalarSize(type)

  size_t stride() const { return count * scalarSize(type); }
  size_t size() const { return stride() == 0 ? 0 : bytes.size() / stride(); }
  void resize(size_t n) { bytes.resize(n * stride()); }

  /// Value `component` of element `i`, converted to double.
  double get(size_t i, uint32_t component = 0) const;
  /// Sets value `component` of element `i` (converted from double to the stored type).
  void set(size_t i, double value, uint32_t component = 0);
};

/// An ordered set of attribute columns with unique names. Columns live in a deque: a reference returned by
/// add() or find() stays valid while further columns are added (not across remove()).
class AttributeSet {
 public:
  using Columns = std::deque<Attribute>;
  /// Adds a column (zero-filled to `n` elements); throws std::invalid_argument if the name exists.
  Attribute& add(const std::string& name, ScalarType type, uint32_t count, size_t n);
  Attribute* find(const std::string& name);
  const Attribute* find(const std::string& name) const;
  bool has(const std::string& name) const { return find(name) != nullptr; }
  void remove(const std::string& name);
  /// Resizes every column to n elements.
  void resize(size_t n);
  /// Appends element `i` of `other` (same column layout required) to every column.
  void appendFrom(const AttributeSet& other, size_t i);
  /// Keeps only the elements whose indices are listed, in that order.
  void select(const std::vector<size_t>& indices);

  const Columns& columns() const { return columns_; }
  Columns& columns() { return columns_; }
  bool empty() const { return columns_.empty(); }

 private:
  Columns columns_;
};

}  // namespace rc
