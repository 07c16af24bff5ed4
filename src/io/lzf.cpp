#include "relaxed_connectivity/io/lzf.h"

#include <algorithm>
#include <cstring>

namespace rc {

namespace {
constexpr unsigned kHashLog = 14;
constexpr size_t kMaxLiteral = 32;      // literal run: control byte 0..31 = length - 1
constexpr size_t kMaxOffset = 1 << 13;  // back reference distance - 1 fits 13 bits
constexpr size_t kMaxMatch = 255 + 7 + 2;

inline uint32_t hash3(const uint8_t* p) {
  const uint32_t v = (uint32_t(p[0]) << 16) | (uint32_t(p[1]) << 8) | p[2];
  return ((v * 2654435761u) >> (32 - kHashLog)) & ((1u << kHashLog) - 1);
}
}  // namespace

std::vector<uint8_t> lzfCompress(const uint8_t* in, size_t size) {
  std::vector<uint8_t> out;
  if (size == 0) return out;
  out.reserve(size + size / kMaxLiteral + 1);
  std::vector<uint32_t> table(size_t(1) << kHashLog, 0);  // position + 1 of the last occurrence, 0 = none
  size_t literal_pos = 0;                                 // index of the pending literal run's control byte
  size_t literals = 0;
  out.push_back(0);
  auto pushLiteral = [&](uint8_t byte) {
    out.push_back(byte);
    if (++literals == kMaxLiteral) {
      out[literal_pos] = kMaxLiteral - 1;
      literals = 0;
      literal_pos = out.size();
      out.push_back(0);
    }
  };
  size_t ip = 0;
  while (ip + 2 < size) {
    uint32_t& slot = table[hash3(in + ip)];
    const size_t candidate = slot;
    slot = static_cast<uint32_t>(ip + 1);
    if (candidate != 0) {
      const size_t ref = candidate - 1;
      const size_t offset = ip - ref - 1;
      if (offset < kMaxOffset && in[ref] == in[ip] && in[ref + 1] == in[ip + 1] &&
          in[ref + 2] == in[ip + 2]) {
        const size_t max_length = std::min(kMaxMatch, size - ip);
        size_t length = 3;
        while (length < max_length && in[ref + length] == in[ip + length]) ++length;
        if (literals > 0)
          out[literal_pos] = static_cast<uint8_t>(literals - 1);
        else
          out.pop_back();  // the empty run's control byte is the last byte
        const size_t code = length - 2;
        if (code < 7) {
          out.push_back(static_cast<uint8_t>((offset >> 8) + (code << 5)));
        } else {
          out.push_back(static_cast<uint8_t>((offset >> 8) + (7 << 5)));
          out.push_back(static_cast<uint8_t>(code - 7));
        }
        out.push_back(static_cast<uint8_t>(offset & 0xff));
        literals = 0;
        literal_pos = out.size();
        out.push_back(0);
        for (size_t k = ip + 1; k < ip + length && k + 2 < size; ++k)
          table[hash3(in + k)] = static_cast<uint32_t>(k + 1);
        ip += length;
        continue;
      }
    }
    pushLiteral(in[ip++]);
  }
  while (ip < size) pushLiteral(in[ip++]);
  if (literals > 0)
    out[literal_pos] = static_cast<uint8_t>(literals - 1);
  else
    out.pop_back();
  return out;
}

size_t lzfDecompress(const uint8_t* in, size_t in_size, uint8_t* out, size_t out_size, std::string* error) {
  size_t ip = 0, op = 0;
  while (ip < in_size) {
    const size_t ctrl = in[ip++];
    if (ctrl < kMaxLiteral) {
      const size_t length = ctrl + 1;
      if (ip + length > in_size) {
        *error = "LZF literal run extends past the end of the compressed data";
        return 0;
      }
      if (op + length > out_size) {
        *error = "LZF data decompresses to more than the expected " + std::to_string(out_size) + " bytes";
        return 0;
      }
      std::memcpy(out + op, in + ip, length);
      ip += length;
      op += length;
      continue;
    }
    size_t length = ctrl >> 5;
    if (length == 7) {
      if (ip >= in_size) {
        *error = "LZF back reference truncated";
        return 0;
      }
      length += in[ip++];
    }
    if (ip >= in_size) {
      *error = "LZF back reference truncated";
      return 0;
    }
    const size_t distance = ((ctrl & 0x1f) << 8) + in[ip++] + 1;
    length += 2;
    if (distance > op) {
      *error = "LZF back reference points before the start of the output";
      return 0;
    }
    if (op + length > out_size) {
      *error = "LZF data decompresses to more than the expected " + std::to_string(out_size) + " bytes";
      return 0;
    }
    const uint8_t* ref = out + op - distance;
    if (distance >= length) {
      std::memcpy(out + op, ref, length);
    } else {
      for (size_t k = 0; k < length; ++k) out[op + k] = ref[k];  // overlapping run
    }
    op += length;
  }
  return op;
}

}  // namespace rc
