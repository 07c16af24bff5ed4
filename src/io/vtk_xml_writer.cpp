#include "relaxed_connectivity/io/vtk_xml_writer.h"

#include <cstdio>
#include <fstream>
#include <sstream>

#include "relaxed_connectivity/io/io_error.h"

namespace rc {

namespace {

struct TypeInfo {
  const char* name;
  size_t size;
};
/// Indexed by VtkXmlType.
constexpr TypeInfo kTypes[] = {{"Float64", 8}, {"Float32", 4}, {"Int64", 8},
                               {"Int32", 4},   {"UInt32", 4},  {"UInt8", 1}};

bool hostIsLittleEndian() {
  const uint16_t one = 1;
  uint8_t first;
  std::memcpy(&first, &one, 1);
  return first == 1;
}

template <typename T>
T valueAt(const uint8_t* bytes) {
  T value;
  std::memcpy(&value, bytes, sizeof(T));
  return value;
}

/// The values of an array as ascii text (floats with round-trip precision), 12 per line.
std::string asciiValues(const VtkXmlArray& a) {
  std::string out;
  char buf[32];
  const size_t size = vtkXmlTypeSize(a.type), n = a.count();
  for (size_t i = 0; i < n; ++i) {
    const uint8_t* v = a.bytes.data() + i * size;
    switch (a.type) {
      case VtkXmlType::kFloat64:
        std::snprintf(buf, sizeof(buf), "%.17g", valueAt<double>(v));
        break;
      case VtkXmlType::kFloat32:
        std::snprintf(buf, sizeof(buf), "%.9g", double(valueAt<float>(v)));
        break;
      case VtkXmlType::kInt64:
        std::snprintf(buf, sizeof(buf), "%lld", (long long)valueAt<int64_t>(v));
        break;
      case VtkXmlType::kInt32:
        std::snprintf(buf, sizeof(buf), "%d", int(valueAt<int32_t>(v)));
        break;
      case VtkXmlType::kUInt32:
        std::snprintf(buf, sizeof(buf), "%u", unsigned(valueAt<uint32_t>(v)));
        break;
      case VtkXmlType::kUInt8:
        std::snprintf(buf, sizeof(buf), "%u", unsigned(*v));
        break;
    }
    out += buf;
    out += (i + 1) % 12 == 0 || i + 1 == n ? '\n' : ' ';
  }
  return out;
}

void writeAttributes(std::ostream& xml, const VtkXmlAttributes& attributes) {
  for (const auto& [name, value] : attributes) xml << ' ' << name << "=\"" << value << '"';
}

}  // namespace

const char* vtkXmlTypeName(VtkXmlType type) {
  return kTypes[size_t(type)].name;
}

size_t vtkXmlTypeSize(VtkXmlType type) {
  return kTypes[size_t(type)].size;
}

void writeVtkXml(const std::string& path, const std::string& dataset_type,
                 const VtkXmlAttributes& piece_attributes, const std::vector<VtkXmlSection>& sections,
                 VtkXmlEncoding encoding) {
  const bool appended = encoding == VtkXmlEncoding::kAppendedRaw;
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n"
      << "<VTKFile type=\"" << dataset_type << "\" version=\"1.0\" byte_order=\""
      << (hostIsLittleEndian() ? "LittleEndian" : "BigEndian") << "\" header_type=\"UInt64\">\n"
      << "  <" << dataset_type << ">\n"
      << "    <Piece";
  writeAttributes(xml, piece_attributes);
  xml << ">\n";
  uint64_t offset = 0;
  for (const VtkXmlSection& section : sections) {
    xml << "      <" << section.tag;
    writeAttributes(xml, section.attributes);
    xml << ">\n";
    for (const VtkXmlArray* a : section.arrays) {
      xml << "        <DataArray type=\"" << vtkXmlTypeName(a->type) << "\" Name=\"" << a->name << "\"";
      if (a->components > 1) xml << " NumberOfComponents=\"" << a->components << "\"";
      if (appended) {
        xml << " format=\"appended\" offset=\"" << offset << "\"/>\n";
        offset += sizeof(uint64_t) + a->bytes.size();
      } else {
        xml << " format=\"ascii\">\n" << asciiValues(*a) << "        </DataArray>\n";
      }
    }
    xml << "      </" << section.tag << ">\n";
  }
  xml << "    </Piece>\n  </" << dataset_type << ">\n";

  std::ofstream out(path, std::ios::binary);
  if (!out) throw IoError(path, "cannot open for writing");
  const std::string text = xml.str();
  out.write(text.data(), std::streamsize(text.size()));
  if (appended) {
    out << "  <AppendedData encoding=\"raw\">\n   _";
    for (const VtkXmlSection& section : sections)
      for (const VtkXmlArray* a : section.arrays) {  // the order of the offsets above
        const uint64_t bytes = a->bytes.size();
        out.write(reinterpret_cast<const char*>(&bytes), sizeof(bytes));
        out.write(reinterpret_cast<const char*>(a->bytes.data()), std::streamsize(bytes));
      }
    out << "\n  </AppendedData>\n";
  }
  out << "</VTKFile>\n";
  if (!out) throw IoError(path, "write failed");
}

}  // namespace rc
