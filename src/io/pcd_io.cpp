#include "relaxed_connectivity/io/pcd_io.h"

#include <algorithm>
#include <string_view>

#include "relaxed_connectivity/io/file_bytes.h"
#include "relaxed_connectivity/io/io_error.h"
#include "relaxed_connectivity/io/lzf.h"
#include "relaxed_connectivity/io/scalar_codec.h"
#include "relaxed_connectivity/io/surfel_fields.h"
#include "relaxed_connectivity/io/text_lines.h"

namespace rc {

namespace {

enum class PcdData { kAscii, kBinary, kBinaryCompressed };

struct PcdHeader {
  std::vector<FieldSpec> fields;
  uint64_t width = 0, height = 0, points = 0;
  PcdData data = PcdData::kAscii;
  size_t data_offset = 0;
  size_t data_first_line = 0;
};

bool pcdType(char letter, int64_t size, ScalarType* type) {
  switch (letter) {
    case 'I':
      if (size == 1)
        *type = ScalarType::kInt8;
      else if (size == 2)
        *type = ScalarType::kInt16;
      else if (size == 4)
        *type = ScalarType::kInt32;
      else
        return false;
      return true;
    case 'U':
      if (size == 1)
        *type = ScalarType::kUInt8;
      else if (size == 2)
        *type = ScalarType::kUInt16;
      else if (size == 4)
        *type = ScalarType::kUInt32;
      else
        return false;
      return true;
    case 'F':
      if (size == 4)
        *type = ScalarType::kFloat32;
      else if (size == 8)
        *type = ScalarType::kFloat64;
      else
        return false;
      return true;
  }
  return false;
}

char pcdTypeLetter(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kInt16:
    case ScalarType::kInt32:
      return 'I';
    case ScalarType::kUInt8:
    case ScalarType::kUInt16:
    case ScalarType::kUInt32:
      return 'U';
    case ScalarType::kFloat32:
    case ScalarType::kFloat64:
      return 'F';
  }
  return '?';
}

PcdHeader parseHeader(const std::string& bytes, const std::string& file) {
  LineReader lines(bytes);
  std::string_view line;
  std::vector<std::string_view> tokens;
  std::vector<std::string_view> names, sizes, types, counts;
  size_t fields_line = 0;
  bool have_width = false, have_height = false, have_points = false, have_data = false;
  PcdHeader header;
  auto number = [&](std::string_view token, const std::string& where, const char* what) {
    int64_t v = -1;
    if (!parseInt64(token, &v) || v < 0)
      throw IoError(file, where, std::string("invalid ") + what + " '" + std::string(token) + "'");
    return static_cast<uint64_t>(v);
  };
  while (!have_data && lines.next(&line)) {
    const std::string where = "header line " + std::to_string(lines.lineNumber());
    splitTokens(stripComment(line), &tokens);
    if (tokens.empty()) continue;
    const std::string_view keyword = tokens[0];
    const std::vector<std::string_view> values(tokens.begin() + 1, tokens.end());
    if (keyword == "VERSION" || keyword == "VIEWPOINT") {
      // the viewpoint (sensor pose) is not part of SurfelCloud
    } else if (keyword == "FIELDS" || keyword == "COLUMNS") {
      names = values;
      fields_line = lines.lineNumber();
    } else if (keyword == "SIZE") {
      sizes = values;
    } else if (keyword == "TYPE") {
      types = values;
    } else if (keyword == "COUNT") {
      counts = values;
    } else if (keyword == "WIDTH" || keyword == "HEIGHT" || keyword == "POINTS") {
      if (values.size() != 1) throw IoError(file, where, std::string(keyword) + " needs one value");
      const uint64_t v = number(values[0], where, std::string(keyword).c_str());
      if (keyword == "WIDTH")
        header.width = v, have_width = true;
      else if (keyword == "HEIGHT")
        header.height = v, have_height = true;
      else
        header.points = v, have_points = true;
    } else if (keyword == "DATA") {
      if (values.size() != 1) throw IoError(file, where, "DATA needs one value");
      if (values[0] == "ascii")
        header.data = PcdData::kAscii;
      else if (values[0] == "binary")
        header.data = PcdData::kBinary;
      else if (values[0] == "binary_compressed")
        header.data = PcdData::kBinaryCompressed;
      else
        throw IoError(file, where, "unsupported DATA encoding '" + std::string(values[0]) + "'");
      have_data = true;
    } else {
      throw IoError(file, where, "unknown header keyword '" + std::string(keyword) + "'");
    }
  }
  if (!have_data) throw IoError(file, "header", "missing DATA line (not a PCD file?)");
  if (names.empty()) throw IoError(file, "header", "missing FIELDS line");
  const std::string fields_where = "header line " + std::to_string(fields_line);
  auto checkLength = [&](const std::vector<std::string_view>& list, const char* what) {
    if (list.size() != names.size())
      throw IoError(file, fields_where,
                    std::string(what) + " has " + std::to_string(list.size()) + " entries but FIELDS has " +
                        std::to_string(names.size()));
  };
  checkLength(sizes, "SIZE");
  checkLength(types, "TYPE");
  if (!counts.empty()) checkLength(counts, "COUNT");
  for (size_t f = 0; f < names.size(); ++f) {
    FieldSpec spec;
    spec.name = std::string(names[f]);
    int64_t size = 0;
    if (!parseInt64(sizes[f], &size) || types[f].size() != 1 || !pcdType(types[f][0], size, &spec.type))
      throw IoError(file, fields_where,
                    "field '" + spec.name + "' has unsupported TYPE " + std::string(types[f]) + " SIZE " +
                        std::string(sizes[f]));
    if (!counts.empty()) {
      const uint64_t count = number(counts[f], fields_where, "COUNT");
      if (count == 0) throw IoError(file, fields_where, "field '" + spec.name + "' has COUNT 0");
      // (PCL's largest descriptors hold a few hundred values per point)
      constexpr uint64_t kMaxCount = uint64_t(1) << 24;
      if (count > kMaxCount)
        throw IoError(file, fields_where,
                      "field '" + spec.name + "' has COUNT " + std::to_string(count) + ", more than " +
                          std::to_string(kMaxCount));
      spec.count = static_cast<uint32_t>(count);
    }
    header.fields.push_back(spec);
  }
  if (!have_points && !have_width) throw IoError(file, "header", "missing POINTS and WIDTH");
  if (!have_width) header.width = header.points, header.height = 1;
  if (!have_height) header.height = header.width == header.points || !have_points ? 1 : 0;
  if (!have_points) header.points = header.width * header.height;
  if (header.width * header.height != header.points)
    throw IoError(file, "header",
                  "WIDTH " + std::to_string(header.width) + " x HEIGHT " + std::to_string(header.height) +
                      " does not match POINTS " + std::to_string(header.points));
  header.data_offset = lines.offset();
  header.data_first_line = lines.lineNumber() + 1;
  return header;
}

std::string pointWhere(size_t i) {
  return "point #" + std::to_string(i);
}

void readAscii(const std::string& bytes, const PcdHeader& header, const std::string& file,
               const std::vector<FieldBinding>& bindings, SurfelCloud* cloud) {
  size_t values_per_point = 0;
  for (const FieldSpec& f : header.fields) values_per_point += f.count;
  LineReader lines(std::string_view(bytes).substr(header.data_offset), header.data_first_line);
  std::string_view line;
  std::vector<std::string_view> tokens;
  uint8_t value[8];
  for (size_t i = 0; i < header.points; ++i) {
    do {
      if (!lines.next(&line))
        throw IoError(file, pointWhere(i),
                      "unexpected end of file (expected " + std::to_string(header.points) + " points)");
      splitTokens(line, &tokens);
    } while (tokens.empty());
    const std::string where = [&] {
      return pointWhere(i) + " (line " + std::to_string(lines.lineNumber()) + ")";
    }();
    if (tokens.size() != values_per_point)
      throw IoError(
          file, where,
          "expected " + std::to_string(values_per_point) + " values, found " + std::to_string(tokens.size()));
    size_t t = 0;
    for (size_t f = 0; f < header.fields.size(); ++f)
      for (uint32_t k = 0; k < header.fields[f].count; ++k, ++t) {
        if (!parseScalar(tokens[t], header.fields[f].type, value))
          throw IoError(file, where,
                        "cannot parse '" + std::string(tokens[t]) + "' as " +
                            scalarName(header.fields[f].type) + " (field '" + header.fields[f].name + "')");
        storeField(bindings[f], i, k, value, cloud);
      }
  }
}

// Row-major records (binary) or field-major arrays (decompressed binary_compressed), little endian.
void readBinary(const uint8_t* data, const PcdHeader& header, bool field_major,
                const std::vector<FieldBinding>& bindings, SurfelCloud* cloud) {
  const bool swap = !hostIsLittleEndian();
  size_t stride = 0;
  for (const FieldSpec& f : header.fields) stride += f.count * scalarSize(f.type);
  const size_t n = header.points;
  size_t field_offset = 0;  // offset of the field in a record, or of its array
  uint8_t value[8];
  for (size_t f = 0; f < header.fields.size(); ++f) {
    const FieldSpec& spec = header.fields[f];
    const size_t size = scalarSize(spec.type);
    const size_t field_bytes = spec.count * size;
    if (bindings[f].target != FieldTarget::kSkip) {
      for (size_t i = 0; i < n; ++i) {
        const uint8_t* p =
            field_major ? data + field_offset * n + i * field_bytes : data + i * stride + field_offset;
        for (uint32_t k = 0; k < spec.count; ++k, p += size) {
          std::memcpy(value, p, size);
          if (swap) reverseBytes(value, size);
          storeField(bindings[f], i, k, value, cloud);
        }
      }
    }
    field_offset += field_bytes;
  }
}

}  // namespace

SurfelCloud readPcdCloud(const std::string& path, const ReadOptions& options) {
  const std::string bytes = readFileBytes(path);
  const PcdHeader header = parseHeader(bytes, path);
  // A POINTS count far beyond what the data can hold is refused before anything is allocated for it (up to
  // twice that, plus 1 KiB of points, the readers below name where the data ends): a point needs its stride
  // in binary, a character and a separator per value in ascii.
  if (header.data != PcdData::kBinaryCompressed) {
    size_t minimum = 0;
    for (const FieldSpec& f : header.fields)
      minimum += header.data == PcdData::kAscii ? 2 * f.count : f.count * scalarSize(f.type);
    const size_t body = bytes.size() - header.data_offset;
    // (the slack is 1 KiB of data, not 1024 points: a point of 16,801 values each made that 137 MB)
    if (minimum > 0 && header.points > 2 * ((body + 1) / minimum) + std::max<size_t>(1, 1024 / minimum))
      throw IoError(path, "header",
                    "POINTS " + std::to_string(header.points) + " of at least " + std::to_string(minimum) +
                        " bytes, but the file has " + std::to_string(body) + " bytes after its header");
  }
  SurfelCloud cloud;
  std::vector<FieldBinding> bindings;
  if (!bindFields(header.fields, FieldNaming::kPcd, header.points, path, "header", &cloud, &bindings))
    throw IoError(path, "header", "missing x, y or z field");
  size_t stride = 0;
  for (const FieldSpec& f : header.fields) stride += f.count * scalarSize(f.type);
  const size_t expected = stride * header.points;
  const auto* data = reinterpret_cast<const uint8_t*>(bytes.data()) + header.data_offset;
  const size_t available = bytes.size() - header.data_offset;

  if (header.data == PcdData::kAscii) {
    readAscii(bytes, header, path, bindings, &cloud);
  } else if (header.data == PcdData::kBinary) {
    if (available < expected)
      throw IoError(path, pointWhere(available / stride),
                    "unexpected end of file (" + std::to_string(header.points) + " points of " +
                        std::to_string(stride) + " bytes need " + std::to_string(expected) +
                        " bytes, found " + std::to_string(available) + ")");
    readBinary(data, header, false, bindings, &cloud);
  } else {
    if (available < 8) throw IoError(path, "compressed data", "unexpected end of file in the size fields");
    uint32_t compressed_size, uncompressed_size;
    std::memcpy(&compressed_size, data, 4);
    std::memcpy(&uncompressed_size, data + 4, 4);
    if (!hostIsLittleEndian()) {
      reverseBytes(reinterpret_cast<uint8_t*>(&compressed_size), 4);
      reverseBytes(reinterpret_cast<uint8_t*>(&uncompressed_size), 4);
    }
    if (uncompressed_size != expected)
      throw IoError(path, "compressed data",
                    "uncompressed size " + std::to_string(uncompressed_size) + " does not match " +
                        std::to_string(header.points) + " points x " + std::to_string(stride) + " bytes");
    if (compressed_size > available - 8)
      throw IoError(path, "compressed data",
                    "unexpected end of file (compressed size " + std::to_string(compressed_size) +
                        ", found " + std::to_string(available - 8) + " bytes)");
    std::vector<uint8_t> raw(expected);
    std::string error;
    const size_t produced = lzfDecompress(data + 8, compressed_size, raw.data(), raw.size(), &error);
    if (!error.empty()) throw IoError(path, "compressed data", error);
    if (produced != expected)
      throw IoError(
          path, "compressed data",
          "decompressed to " + std::to_string(produced) + " bytes, expected " + std::to_string(expected));
    readBinary(raw.data(), header, true, bindings, &cloud);
  }
  if (header.height > 1) {
    cloud.width = static_cast<uint32_t>(header.width);
    cloud.height = static_cast<uint32_t>(header.height);
  }
  applyReadOptions(options, &cloud);
  return cloud;
}

void writePcdCloud(const std::string& path, const SurfelCloud& cloud, const WriteOptions& options) {
  std::vector<FieldSpec> fields;
  std::vector<FieldBinding> bindings;
  describeCloudFields(cloud, FieldNaming::kPcd, options.double_precision, path, &fields, &bindings);
  const size_t n = cloud.size();
  const bool organized = cloud.isOrganized();
  std::string out = "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS";
  for (const FieldSpec& f : fields) out += " " + f.name;
  out += "\nSIZE";
  for (const FieldSpec& f : fields) out += " " + std::to_string(scalarSize(f.type));
  out += "\nTYPE";
  for (const FieldSpec& f : fields) (out += ' ') += pcdTypeLetter(f.type);
  out += "\nCOUNT";
  for (const FieldSpec& f : fields) out += " " + std::to_string(f.count);
  out += "\nWIDTH " + std::to_string(organized ? cloud.width : n);
  out += "\nHEIGHT " + std::to_string(organized ? cloud.height : 1);
  out += "\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS " + std::to_string(n) + "\nDATA ";
  out += options.encoding == Encoding::kAscii    ? "ascii\n"
         : options.encoding == Encoding::kBinary ? "binary\n"
                                                 : "binary_compressed\n";
  size_t stride = 0;
  for (const FieldSpec& f : fields) stride += f.count * scalarSize(f.type);
  const bool swap = !hostIsLittleEndian();

  if (options.encoding == Encoding::kAscii) {
    uint8_t value[8];
    for (size_t i = 0; i < n; ++i) {
      for (size_t f = 0; f < fields.size(); ++f)
        for (uint32_t k = 0; k < fields[f].count; ++k) {
          loadField(bindings[f], i, k, cloud, value);
          if (f + k > 0) out += ' ';
          appendScalarText(value, fields[f].type, &out);
        }
      out += '\n';
    }
  } else {
    const bool field_major = options.encoding == Encoding::kBinaryCompressed;
    std::vector<uint8_t> raw(n * stride);
    size_t field_offset = 0;
    for (size_t f = 0; f < fields.size(); ++f) {
      const size_t size = scalarSize(fields[f].type);
      const size_t field_bytes = fields[f].count * size;
      for (size_t i = 0; i < n; ++i) {
        uint8_t* p = field_major ? raw.data() + field_offset * n + i * field_bytes
                                 : raw.data() + i * stride + field_offset;
        for (uint32_t k = 0; k < fields[f].count; ++k, p += size) {
          loadField(bindings[f], i, k, cloud, p);
          if (swap) reverseBytes(p, size);
        }
      }
      field_offset += field_bytes;
    }
    if (!field_major) {
      out.append(reinterpret_cast<const char*>(raw.data()), raw.size());
    } else {
      const std::vector<uint8_t> packed = lzfCompress(raw.data(), raw.size());
      uint32_t sizes[2] = {static_cast<uint32_t>(packed.size()), static_cast<uint32_t>(raw.size())};
      if (swap) {
        reverseBytes(reinterpret_cast<uint8_t*>(&sizes[0]), 4);
        reverseBytes(reinterpret_cast<uint8_t*>(&sizes[1]), 4);
      }
      out.append(reinterpret_cast<const char*>(sizes), 8);
      out.append(reinterpret_cast<const char*>(packed.data()), packed.size());
    }
  }
  writeFileBytes(path, out);
}

}  // namespace rc
