#include "relaxed_connectivity/io/ply_io.h"

#include <algorithm>
#include <string_view>
#include <utility>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/scalar_codec.h"
#include "relaxed_connectivity/io/surfel_fields.h"
#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

namespace {

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyProperty {
  std::string name;
  ScalarType type = ScalarType::kFloat32;  ///< list items for list properties
  bool is_list = false;
  ScalarType count_type = ScalarType::kUInt8;
};

struct PlyElement {
  std::string name;
  size_t count = 0;
  std::vector<PlyProperty> properties;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::kAscii;
  std::vector<PlyElement> elements;
  size_t data_offset = 0;
  size_t data_first_line = 0;
};

bool plyTypeFromName(std::string_view name, ScalarType* type) {
  static const std::pair<const char*, ScalarType> kTypes[] = {
      {"char", ScalarType::kInt8},      {"int8", ScalarType::kInt8},       {"uchar", ScalarType::kUInt8},
      {"uint8", ScalarType::kUInt8},    {"short", ScalarType::kInt16},     {"int16", ScalarType::kInt16},
      {"ushort", ScalarType::kUInt16},  {"uint16", ScalarType::kUInt16},   {"int", ScalarType::kInt32},
      {"int32", ScalarType::kInt32},    {"uint", ScalarType::kUInt32},     {"uint32", ScalarType::kUInt32},
      {"float", ScalarType::kFloat32},  {"float32", ScalarType::kFloat32}, {"double", ScalarType::kFloat64},
      {"float64", ScalarType::kFloat64}};
  for (const auto& t : kTypes)
    if (name == t.first) {
      *type = t.second;
      return true;
    }
  return false;
}

const char* plyTypeName(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return "char";
    case ScalarType::kUInt8:
      return "uchar";
    case ScalarType::kInt16:
      return "short";
    case ScalarType::kUInt16:
      return "ushort";
    case ScalarType::kInt32:
      return "int";
    case ScalarType::kUInt32:
      return "uint";
    case ScalarType::kFloat32:
      return "float";
    case ScalarType::kFloat64:
      return "double";
  }
  return "?";
}

bool isIntegerType(ScalarType type) {
  return type != ScalarType::kFloat32 && type != ScalarType::kFloat64;
}

PlyHeader parseHeader(const std::string& bytes, const std::string& file) {
  LineReader lines(bytes);
  std::string_view line;
  if (!lines.next(&line) || trimBlanks(line) != "ply")
    throw IoError(file, "line 1", "not a PLY file (the first line is not 'ply')");
  PlyHeader header;
  bool have_format = false, ended = false;
  std::vector<std::string_view> tokens;
  while (!ended && lines.next(&line)) {
    const std::string where = "header line " + std::to_string(lines.lineNumber());
    splitTokens(line, &tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    if (keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "end_header") {
      ended = true;
    } else if (keyword == "format") {
      if (tokens.size() < 2) throw IoError(file, where, "format line without a format");
      if (tokens[1] == "ascii")
        header.format = PlyFormat::kAscii;
      else if (tokens[1] == "binary_little_endian")
        header.format = PlyFormat::kBinaryLittleEndian;
      else if (tokens[1] == "binary_big_endian")
        header.format = PlyFormat::kBinaryBigEndian;
      else
        throw IoError(file, where, "unknown format '" + std::string(tokens[1]) + "'");
      have_format = true;
    } else if (keyword == "element") {
      int64_t count = -1;
      if (tokens.size() != 3 || !parseInt64(tokens[2], &count) || count < 0)
        throw IoError(file, where, "malformed element line '" + std::string(line) + "'");
      for (const PlyElement& earlier : header.elements)
        if (earlier.name == tokens[1])
          throw IoError(file, where, "element '" + earlier.name + "' declared twice");
      header.elements.push_back(PlyElement{std::string(tokens[1]), static_cast<size_t>(count), {}});
    } else if (keyword == "property") {
      if (header.elements.empty()) throw IoError(file, where, "property before any element");
      PlyProperty property;
      if (tokens.size() == 5 && tokens[1] == "list") {
        property.is_list = true;
        if (!plyTypeFromName(tokens[2], &property.count_type) || !isIntegerType(property.count_type))
          throw IoError(file, where, "unsupported list length type '" + std::string(tokens[2]) + "'");
        if (!plyTypeFromName(tokens[3], &property.type))
          throw IoError(file, where, "unknown property type '" + std::string(tokens[3]) + "'");
        property.name = std::string(tokens[4]);
      } else if (tokens.size() == 3) {
        if (!plyTypeFromName(tokens[1], &property.type))
          throw IoError(file, where, "unknown property type '" + std::string(tokens[1]) + "'");
        property.name = std::string(tokens[2]);
      } else {
        throw IoError(file, where, "malformed property line '" + std::string(line) + "'");
      }
      header.elements.back().properties.push_back(std::move(property));
    } else {
      throw IoError(file, where, "unknown header keyword '" + std::string(keyword) + "'");
    }
  }
  if (!ended) throw IoError(file, "header", "missing end_header");
  if (!have_format) throw IoError(file, "header", "missing format line");
  header.data_offset = lines.offset();
  header.data_first_line = lines.lineNumber() + 1;
  return header;
}

// Values of a binary body (converted to host byte order).
class BinarySource {
 public:
  BinarySource(const uint8_t* begin, const uint8_t* end, bool swap) : p_(begin), end_(end), swap_(swap) {}
  bool read(ScalarType type, uint8_t* out) {
    const size_t size = scalarSize(type);
    if (static_cast<size_t>(end_ - p_) < size) return false;
    std::memcpy(out, p_, size);
    if (swap_) reverseBytes(out, size);
    p_ += size;
    return true;
  }
  bool skip(ScalarType type, size_t n) {
    if (n > static_cast<size_t>(end_ - p_) / scalarSize(type)) return false;  // (n * size could overflow)
    p_ += n * scalarSize(type);
    return true;
  }
  std::string problem() const { return "unexpected end of file"; }
  std::string location() const { return ""; }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
  bool swap_;
};

// Values of an ascii body: whitespace-separated tokens, records usually one per line.
class AsciiSource {
 public:
  AsciiSource(std::string_view text, size_t first_line) : lines_(text, first_line) {}
  bool read(ScalarType type, uint8_t* out) {
    std::string_view token;
    if (!nextToken(&token)) return false;
    if (!parseScalar(token, type, out)) {
      problem_ = "cannot parse '" + std::string(token) + "' as " + scalarName(type);
      return false;
    }
    return true;
  }
  bool skip(ScalarType, size_t n) {
    std::string_view token;
    for (size_t k = 0; k < n; ++k)
      if (!nextToken(&token)) return false;
    return true;
  }
  std::string problem() const { return problem_; }
  std::string location() const { return " (line " + std::to_string(lines_.lineNumber()) + ")"; }

 private:
  bool nextToken(std::string_view* token) {
    while (index_ >= tokens_.size()) {
      std::string_view line;
      if (!lines_.next(&line)) {
        problem_ = "unexpected end of file";
        return false;
      }
      splitTokens(line, &tokens_);
      index_ = 0;
    }
    *token = tokens_[index_++];
    return true;
  }
  LineReader lines_;
  std::vector<std::string_view> tokens_;
  size_t index_ = 0;
  std::string problem_;
};

// Vertex properties as field specs: scalar properties name_0, name_1, ... of one type become one field.
struct PropertySlot {
  int field = -1;  ///< -1 for list properties (skipped)
  uint32_t component = 0;
};

void groupVertexProperties(const PlyElement& element, std::vector<FieldSpec>* fields,
                           std::vector<PropertySlot>* slots) {
  const auto& props = element.properties;
  fields->clear();
  slots->assign(props.size(), PropertySlot());
  for (size_t p = 0; p < props.size();) {
    if (props[p].is_list) {
      ++p;
      continue;
    }
    const std::string& name = props[p].name;
    uint32_t run = 1;
    if (name.size() > 2 && name.compare(name.size() - 2, 2, "_0") == 0) {
      const std::string base = name.substr(0, name.size() - 2);
      while (p + run < props.size() && !props[p + run].is_list && props[p + run].type == props[p].type &&
             props[p + run].name == base + "_" + std::to_string(run))
        ++run;
      if (run >= 2) {
        for (uint32_t k = 0; k < run; ++k)
          (*slots)[p + k] = PropertySlot{static_cast<int>(fields->size()), k};
        fields->push_back(FieldSpec{base, props[p].type, run});
        p += run;
        continue;
      }
    }
    (*slots)[p] = PropertySlot{static_cast<int>(fields->size()), 0};
    fields->push_back(FieldSpec{name, props[p].type, 1});
    ++p;
  }
}

int findIndexList(const PlyElement& element) {
  for (size_t p = 0; p < element.properties.size(); ++p) {
    const PlyProperty& prop = element.properties[p];
    if (prop.is_list && (prop.name == "vertex_indices" || prop.name == "vertex_index"))
      return static_cast<int>(p);
  }
  return -1;
}

template <class Source>
class ElementReader {
 public:
  ElementReader(Source* source, const std::string& file) : src_(*source), file_(file) {}

  void readVertices(const PlyElement& element, SurfelCloud* cloud) {
    std::vector<FieldSpec> fields;
    std::vector<PropertySlot> slots;
    groupVertexProperties(element, &fields, &slots);
    std::vector<FieldBinding> bindings;
    const std::string where = "element '" + element.name + "'";
    if (!bindFields(fields, FieldNaming::kPly, element.count, file_, where, cloud, &bindings))
      throw IoError(file_, where, "missing x, y or z property");
    uint8_t value[8];
    const auto& props = element.properties;
    for (size_t i = 0; i < element.count; ++i) {
      for (size_t p = 0; p < props.size(); ++p) {
        if (props[p].is_list) {
          skipList(element, i, props[p]);
          continue;
        }
        if (!src_.read(props[p].type, value)) fail(element, i, src_.problem());
        storeField(bindings[slots[p].field], i, slots[p].component, value, cloud);
      }
    }
  }

  // Polygons of a `face` element, triangulated as fans.
  void readFaces(const PlyElement& element, size_t vertex_count, std::vector<Triangle>* triangles) {
    const int list = findIndexList(element);
    if (list < 0) throw IoError(file_, "element '" + element.name + "'", "no vertex_indices list property");
    triangles->reserve(triangles->size() + element.count);
    for (size_t i = 0; i < element.count; ++i) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        if (static_cast<int>(p) != list) {
          skipProperty(element, i, element.properties[p]);
          continue;
        }
        readIndexList(element, i, element.properties[p]);
        if (indices_.size() < 3) continue;
        for (int64_t index : indices_) checkIndex(element, i, index, vertex_count);
        for (size_t k = 1; k + 1 < indices_.size(); ++k)
          triangles->push_back(
              Triangle{uint32_t(indices_[0]), uint32_t(indices_[k]), uint32_t(indices_[k + 1])});
      }
    }
  }

  // Triangle strips of a `tristrips` element; -1 restarts a strip.
  void readStrips(const PlyElement& element, size_t vertex_count, std::vector<Triangle>* triangles) {
    const int list = findIndexList(element);
    if (list < 0) throw IoError(file_, "element '" + element.name + "'", "no vertex_indices list property");
    for (size_t i = 0; i < element.count; ++i) {
      for (size_t p = 0; p < element.properties.size(); ++p) {
        if (static_cast<int>(p) != list) {
          skipProperty(element, i, element.properties[p]);
          continue;
        }
        readIndexList(element, i, element.properties[p]);
        size_t start = 0;
        for (size_t k = 0; k <= indices_.size(); ++k) {
          if (k < indices_.size() && indices_[k] != -1) continue;
          for (size_t j = start; j + 2 < k; ++j) {
            int64_t a = indices_[j], b = indices_[j + 1];
            const int64_t c = indices_[j + 2];
            checkIndex(element, i, a, vertex_count);
            checkIndex(element, i, b, vertex_count);
            checkIndex(element, i, c, vertex_count);
            if ((j - start) & 1) std::swap(a, b);  // every other strip triangle has flipped winding
            if (a == b || b == c || a == c) continue;
            triangles->push_back(Triangle{uint32_t(a), uint32_t(b), uint32_t(c)});
          }
          start = k + 1;
        }
      }
    }
  }

  void skipElement(const PlyElement& element) {
    // (an element without properties holds no bytes, whatever its count: fuzz_ply declared 1e9 of them)
    if (element.properties.empty()) return;
    for (size_t i = 0; i < element.count; ++i)
      for (const PlyProperty& prop : element.properties) skipProperty(element, i, prop);
  }

 private:
  [[noreturn]] void fail(const PlyElement& element, size_t i, const std::string& problem) {
    throw IoError(file_, "element '" + element.name + "' #" + std::to_string(i) + src_.location(), problem);
  }
  void checkIndex(const PlyElement& element, size_t i, int64_t index, size_t vertex_count) {
    if (index < 0 || static_cast<uint64_t>(index) >= vertex_count)
      fail(element, i,
           "vertex index " + std::to_string(index) + " out of range [0, " + std::to_string(vertex_count) +
               ")");
  }
  int64_t readListLength(const PlyElement& element, size_t i, const PlyProperty& prop) {
    uint8_t value[8];
    if (!src_.read(prop.count_type, value)) fail(element, i, src_.problem());
    const int64_t n = scalarToInt64(value, prop.count_type);
    if (n < 0) fail(element, i, "negative list length " + std::to_string(n) + " in '" + prop.name + "'");
    return n;
  }
  void skipList(const PlyElement& element, size_t i, const PlyProperty& prop) {
    const int64_t n = readListLength(element, i, prop);
    if (!src_.skip(prop.type, static_cast<size_t>(n))) fail(element, i, src_.problem());
  }
  void skipProperty(const PlyElement& element, size_t i, const PlyProperty& prop) {
    if (prop.is_list)
      skipList(element, i, prop);
    else if (!src_.skip(prop.type, 1))
      fail(element, i, src_.problem());
  }
  void readIndexList(const PlyElement& element, size_t i, const PlyProperty& prop) {
    const int64_t n = readListLength(element, i, prop);
    // Grown as read: a list length beyond the data fails where the data ends, not in an allocation of the
    // length (a binary list of 2^32 entries asked for 32 GB, found by fuzzing).
    indices_.clear();
    uint8_t value[8];
    for (int64_t k = 0; k < n; ++k) {
      if (!src_.read(prop.type, value)) fail(element, i, src_.problem());
      indices_.push_back(scalarToInt64(value, prop.type));
    }
  }

  Source& src_;
  const std::string& file_;
  std::vector<int64_t> indices_;
};

template <class Source>
void readBody(Source* source, const PlyHeader& header, const std::string& file, bool want_faces,
              TriangleMesh* mesh) {
  size_t vertex_count = 0;
  bool has_vertices = false;
  for (const PlyElement& element : header.elements)
    if (element.name == "vertex") {
      vertex_count = element.count;
      has_vertices = true;
    }
  if (!has_vertices) throw IoError(file, "header", "no 'vertex' element");
  ElementReader<Source> reader(source, file);
  bool vertices_read = false;
  for (const PlyElement& element : header.elements) {
    if (element.name == "vertex" && !vertices_read) {
      reader.readVertices(element, &mesh->vertices);
      vertices_read = true;
      if (!want_faces) return;
    } else if (want_faces && element.name == "face") {
      reader.readFaces(element, vertex_count, &mesh->triangles);
    } else if (want_faces && element.name == "tristrips") {
      reader.readStrips(element, vertex_count, &mesh->triangles);
    } else {
      reader.skipElement(element);
    }
  }
}

/// Refuses an element whose declared count is far beyond what the file can hold, before anything is allocated
/// for it: each element needs at least its properties' bytes (binary: a scalar each, a list its count; ascii:
/// a character and a separator each). Up to twice that (plus 1 KiB) the reader goes on and names the element
/// where the data ends, so what it allocates stays proportional to the file.
void checkElementCounts(const PlyHeader& header, size_t body_bytes, const std::string& file) {
  for (const PlyElement& element : header.elements) {
    size_t minimum = 0;
    for (const PlyProperty& p : element.properties)
      minimum += header.format == PlyFormat::kAscii ? 2 : scalarSize(p.is_list ? p.count_type : p.type);
    if (minimum == 0) continue;
    const size_t capacity = (body_bytes + 1) / minimum;
    if (element.count <= 2 * capacity + std::max<size_t>(1, 1024 / minimum)) continue;  // (1 KiB of slack)
    throw IoError(file, "element '" + element.name + "'",
                  "declares " + std::to_string(element.count) + " elements of at least " +
                      std::to_string(minimum) + " bytes, but the file has " + std::to_string(body_bytes) +
                      " bytes after its header");
  }
}

TriangleMesh readPly(const std::string& path, bool want_faces) {
  const std::string bytes = readFileBytes(path);
  const PlyHeader header = parseHeader(bytes, path);
  checkElementCounts(header, bytes.size() - header.data_offset, path);
  TriangleMesh mesh;
  if (header.format == PlyFormat::kAscii) {
    AsciiSource source(std::string_view(bytes).substr(header.data_offset), header.data_first_line);
    readBody(&source, header, path, want_faces, &mesh);
  } else {
    const bool file_little_endian = header.format == PlyFormat::kBinaryLittleEndian;
    const auto* begin = reinterpret_cast<const uint8_t*>(bytes.data());
    BinarySource source(begin + header.data_offset, begin + bytes.size(),
                        file_little_endian != hostIsLittleEndian());
    readBody(&source, header, path, want_faces, &mesh);
  }
  return mesh;
}

void writePly(const std::string& path, const SurfelCloud& cloud, const std::vector<Triangle>* triangles,
              const WriteOptions& options) {
  if (options.encoding == Encoding::kBinaryCompressed)
    throw IoError(path, "PLY has no binary_compressed encoding (use kAscii or kBinary)");
  const bool ascii = options.encoding == Encoding::kAscii;
  std::vector<FieldSpec> fields;
  std::vector<FieldBinding> bindings;
  describeCloudFields(cloud, FieldNaming::kPly, options.double_precision, path, &fields, &bindings);
  const size_t n = cloud.size();
  if (triangles)
    for (size_t t = 0; t < triangles->size(); ++t)
      for (uint32_t index : (*triangles)[t])
        if (index >= n)
          throw IoError(
              path, "triangle #" + std::to_string(t),
              "vertex index " + std::to_string(index) + " out of range [0, " + std::to_string(n) + ")");

  std::string out = "ply\nformat ";
  out += ascii ? "ascii" : options.big_endian ? "binary_big_endian" : "binary_little_endian";
  out += " 1.0\ncomment written by relaxed_connectivity\nelement vertex " + std::to_string(n) + "\n";
  size_t stride = 0;
  for (const FieldSpec& f : fields) {
    stride += f.count * scalarSize(f.type);
    if (f.count == 1) {
      out += std::string("property ") + plyTypeName(f.type) + " " + f.name + "\n";
    } else {
      for (uint32_t k = 0; k < f.count; ++k)
        out += std::string("property ") + plyTypeName(f.type) + " " + f.name + "_" + std::to_string(k) + "\n";
    }
  }
  if (triangles)
    out += "element face " + std::to_string(triangles->size()) + "\nproperty list uchar int vertex_indices\n";
  out += "end_header\n";

  uint8_t value[8];
  if (ascii) {
    for (size_t i = 0; i < n; ++i) {
      for (size_t f = 0; f < fields.size(); ++f)
        for (uint32_t k = 0; k < fields[f].count; ++k) {
          loadField(bindings[f], i, k, cloud, value);
          if (f + k > 0) out += ' ';
          appendScalarText(value, fields[f].type, &out);
        }
      out += '\n';
    }
    if (triangles)
      for (const Triangle& t : *triangles)
        out += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  } else {
    const bool swap = options.big_endian == hostIsLittleEndian();
    const size_t header_size = out.size();
    out.resize(header_size + n * stride + (triangles ? triangles->size() * 13 : 0));
    uint8_t* p = reinterpret_cast<uint8_t*>(&out[header_size]);
    for (size_t i = 0; i < n; ++i)
      for (size_t f = 0; f < fields.size(); ++f) {
        const size_t size = scalarSize(fields[f].type);
        for (uint32_t k = 0; k < fields[f].count; ++k) {
          loadField(bindings[f], i, k, cloud, p);
          if (swap) reverseBytes(p, size);
          p += size;
        }
      }
    if (triangles)
      for (const Triangle& t : *triangles) {
        *p++ = 3;
        for (uint32_t index : t) {
          const int32_t v = static_cast<int32_t>(index);
          std::memcpy(p, &v, 4);
          if (swap) reverseBytes(p, 4);
          p += 4;
        }
      }
  }
  writeFileBytes(path, out);
}

}  // namespace

SurfelCloud readPlyCloud(const std::string& path, const ReadOptions& options) {
  SurfelCloud cloud = std::move(readPly(path, false).vertices);
  applyReadOptions(options, &cloud);
  return cloud;
}

TriangleMesh readPlyMesh(const std::string& path, const ReadOptions& options) {
  TriangleMesh mesh = readPly(path, true);
  applyReadOptions(options, &mesh);
  return mesh;
}

void writePlyCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options) {
  writePly(path, cloud, nullptr, options);
}

void writePlyMesh(const std::string& path, const TriangleMesh& mesh, const WriteOptions& options) {
  writePly(path, mesh.vertices, &mesh.triangles, options);
}

}  // namespace rc
