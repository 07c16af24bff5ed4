#include "relaxed_connectivity/core/attribute.h"

#include <algorithm>

namespace rc {

size_t scalarSize(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
    case ScalarType::kUInt8:
      return 1;
    case ScalarType::kInt16:
    case ScalarType::kUInt16:
      return 2;
    case ScalarType::kInt32:
    case ScalarType::kUInt32:
    case ScalarType::kFloat32:
      return 4;
    case ScalarType::kFloat64:
      return 8;
  }
  return 0;
}

const char* scalarName(ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return "int8";
    case ScalarType::kUInt8:
      return "uint8";
    case ScalarType::kInt16:
      return "int16";
    case ScalarType::kUInt16:
      return "uint16";
    case ScalarType::kInt32:
      return "int32";
    case ScalarType::kUInt32:
      return "uint32";
    case ScalarType::kFloat32:
      return "float32";
    case ScalarType::kFloat64:
      return "float64";
  }
  return "?";
}

namespace {
template <typename T>
T load(const uint8_t* p) {
  T v;
  std::memcpy(&v, p, sizeof(T));
  return v;
}
template <typename T>
void store(uint8_t* p, double v) {
  const T t = static_cast<T>(v);
  std::memcpy(p, &t, sizeof(T));
}
}  // namespace

double scalarToDouble(const uint8_t* p, ScalarType type) {
  switch (type) {
    case ScalarType::kInt8:
      return load<int8_t>(p);
    case ScalarType::kUInt8:
      return load<uint8_t>(p);
    case ScalarType::kInt16:
      return load<int16_t>(p);
    case ScalarType::kUInt16:
      return load<uint16_t>(p);
    case ScalarType::kInt32:
      return load<int32_t>(p);
    case ScalarType::kUInt32:
      return load<uint32_t>(p);
    case ScalarType::kFloat32:
      return load<float>(p);
    case ScalarType::kFloat64:
      return load<double>(p);
  }
  return 0.0;
}

void doubleToScalar(double value, ScalarType type, uint8_t* out) {
  switch (type) {
    case ScalarType::kInt8:
      store<int8_t>(out, value);
      break;
    case ScalarType::kUInt8:
      store<uint8_t>(out, value);
      break;
    case ScalarType::kInt16:
      store<int16_t>(out, value);
      break;
    case ScalarType::kUInt16:
      store<uint16_t>(out, value);
      break;
    case ScalarType::kInt32:
      store<int32_t>(out, value);
      break;
    case ScalarType::kUInt32:
      store<uint32_t>(out, value);
      break;
    case ScalarType::kFloat32:
      store<float>(out, value);
      break;
    case ScalarType::kFloat64:
      store<double>(out, value);
      break;
  }
}

double Attribute::get(size_t i, uint32_t component) const {
  return scalarToDouble(bytes.data() + i * stride() + component * scalarSize(type), type);
}

void Attribute::set(size_t i, double value, uint32_t component) {
  doubleToScalar(value, type, bytes.data() + i * stride() + component * scalarSize(type));
}

Attribute& AttributeSet::add(const std::string& name, ScalarType type, uint32_t count, size_t n) {
  if (has(name)) throw std::invalid_argument("attribute '" + name + "' already exists");
  if (count == 0) throw std::invalid_argument("attribute '" + name + "' has a count of zero");
  Attribute a;
  a.name = name;
  a.type = type;
  a.count = count;
  a.resize(n);
  columns_.push_back(std::move(a));
  return columns_.back();
}

Attribute* AttributeSet::find(const std::string& name) {
  for (auto& c : columns_)
    if (c.name == name) return &c;
  return nullptr;
}

const Attribute* AttributeSet::find(const std::string& name) const {
  for (const auto& c : columns_)
    if (c.name == name) return &c;
  return nullptr;
}

void AttributeSet::remove(const std::string& name) {
  columns_.erase(
      std::remove_if(columns_.begin(), columns_.end(), [&](const Attribute& a) { return a.name == name; }),
      columns_.end());
}

void AttributeSet::resize(size_t n) {
  for (auto& c : columns_) c.resize(n);
}

void AttributeSet::appendFrom(const AttributeSet& other, size_t i) {
  if (other.columns_.size() != columns_.size())
    throw std::invalid_argument("appendFrom: attribute sets have different columns");
  for (size_t c = 0; c < columns_.size(); ++c) {
    const Attribute& src = other.columns_[c];
    Attribute& dst = columns_[c];
    if (src.name != dst.name || src.type != dst.type || src.count != dst.count)
      throw std::invalid_argument("appendFrom: attribute '" + dst.name + "' differs in layout");
    const uint8_t* p = src.bytes.data() + i * src.stride();
    dst.bytes.insert(dst.bytes.end(), p, p + src.stride());
  }
}

void AttributeSet::select(const std::vector<size_t>& indices) {
  for (auto& c : columns_) {
    std::vector<uint8_t> out(indices.size() * c.stride());
    for (size_t k = 0; k < indices.size(); ++k)
      std::memcpy(out.data() + k * c.stride(), c.bytes.data() + indices[k] * c.stride(), c.stride());
    c.bytes.swap(out);
  }
}

}  // namespace rc
