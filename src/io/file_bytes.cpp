#include "relaxed_connectivity/io/file_bytes.h"

#include <cctype>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>

#include "relaxed_connectivity/io/io_error.h"

namespace rc {

namespace {
struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};
using FilePtr = std::unique_ptr<std::FILE, FileCloser>;
}  // namespace

std::string readFileBytes(const std::string& path) {
  FilePtr file(std::fopen(path.c_str(), "rb"));
  if (!file) throw IoError(path, std::string("cannot open file: ") + std::strerror(errno));
  if (std::fseek(file.get(), 0, SEEK_END) != 0) throw IoError(path, "cannot seek (not a regular file?)");
  const long size = std::ftell(file.get());
  if (size < 0) throw IoError(path, "cannot determine the file size");
  std::rewind(file.get());
  std::string bytes(static_cast<size_t>(size), '\0');
  if (size > 0 && std::fread(&bytes[0], 1, bytes.size(), file.get()) != bytes.size())
    throw IoError(path, std::string("read error: ") + std::strerror(errno));
  return bytes;
}

void writeFileBytes(const std::string& path, const std::string& bytes) {
  FilePtr file(std::fopen(path.c_str(), "wb"));
  if (!file) throw IoError(path, std::string("cannot create file: ") + std::strerror(errno));
  if (!bytes.empty() && std::fwrite(bytes.data(), 1, bytes.size(), file.get()) != bytes.size())
    throw IoError(path, std::string("write error: ") + std::strerror(errno));
  if (std::fclose(file.release()) != 0)
    throw IoError(path, std::string("write error: ") + std::strerror(errno));
}

std::string lowerCaseExtension(const std::string& path) {
  const size_t slash = path.find_last_of("/\\");
  const size_t dot = path.find_last_of('.');
  if (dot == std::string::npos || (slash != std::string::npos && dot < slash)) return "";
  std::string ext = path.substr(dot);
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return ext;
}

}  // namespace rc
