// LZF compression in the liblzf stream format, as used by the PCD binary_compressed encoding.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace rc {

/// Compresses `size` bytes. Output is at most size + size / 32 + 1 bytes (incompressible data).
std::vector<uint8_t> lzfCompress(const uint8_t* data, size_t size);

/// Decompresses `in` into `out` (capacity out_size). Returns the number of bytes produced, or sets `error`
/// (corrupt stream or output overflow) and returns 0.
size_t lzfDecompress(const uint8_t* in, size_t in_size, uint8_t* out, size_t out_size, std::string* error);

}  // namespace rc
