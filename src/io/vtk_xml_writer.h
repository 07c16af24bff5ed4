// VTK XML dataset files (.vtp, .vtu, ...) for ParaView: arrays as raw host-order bytes, written either as
// ascii text inside each DataArray or as one raw AppendedData block (header_type UInt64).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace rc {

/// The order indexes the name / size table in vtk_xml_writer.cpp.
enum class VtkXmlType { kFloat64, kFloat32, kInt64, kInt32, kUInt32, kUInt8 };

/// "Float64", "Float32", "Int64", "Int32", "UInt32", "UInt8".
const char* vtkXmlTypeName(VtkXmlType type);
size_t vtkXmlTypeSize(VtkXmlType type);

/// One DataArray: values appended with put<T>() in host byte order (T must match `type`).
struct VtkXmlArray {
  std::string name;
  VtkXmlType type;
  int components = 1;
  std::vector<uint8_t> bytes;

  template <typename T>
  void put(T value) {
    const size_t at = bytes.size();
    bytes.resize(at + sizeof(T));
    std::memcpy(bytes.data() + at, &value, sizeof(T));
  }
  /// Number of scalar values (tuples times components).
  size_t count() const { return bytes.size() / vtkXmlTypeSize(type); }
};

/// Attributes of an XML element, written in order as ` name="value"`.
using VtkXmlAttributes = std::vector<std::pair<std::string, std::string>>;

/// One child of the Piece element (PointData, CellData, Points, Cells, Verts, ...) with its arrays, which
/// must outlive the write.
struct VtkXmlSection {
  std::string tag;
  VtkXmlAttributes attributes;
  std::vector<const VtkXmlArray*> arrays;
};

enum class VtkXmlEncoding { kAscii, kAppendedRaw };

/// Writes `<VTKFile type="dataset_type">` with one Piece (`piece_attributes`, e.g. NumberOfPoints) holding
/// the sections in order. kAscii prints the values (floats with round-trip precision, 12 per line);
/// kAppendedRaw stores each array as a UInt64 byte count plus its bytes in declaration order. Throws
/// IoError if the file cannot be written.
void writeVtkXml(const std::string& path, const std::string& dataset_type,
                 const VtkXmlAttributes& piece_attributes, const std::vector<VtkXmlSection>& sections,
                 VtkXmlEncoding encoding);

}  // namespace rc
