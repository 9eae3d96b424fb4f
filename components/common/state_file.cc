#include "common/state_file.h"

#include <zlib.h>

#include <cstdio>
#include <fstream>
#include <sstream>

namespace sarmap {
namespace common {
namespace {

std::string Header(const std::string& kind, int version, size_t size, uint32_t crc) {
  char hex[9];
  std::snprintf(hex, sizeof(hex), "%08x", crc);
  return "# sarmap-state " + kind + " v" + std::to_string(version) + " bytes " +
         std::to_string(size) + " crc32 " + hex + "\n";
}

constexpr char kPrefix[] = "# sarmap-state ";

}  // namespace

uint32_t Crc32(const void* data, size_t size, uint32_t crc) {
  // zlib's braided CRC: a large state file (SLAM's grows to tens of MB, saved every few
  // seconds) costs a few ms, where a byte-at-a-time table costs tens. (zlib answers 0 for a
  // null buffer, whatever crc it continues.)
  if (size == 0) return crc;
  return static_cast<uint32_t>(crc32_z(crc, static_cast<const Bytef*>(data), size));
}

void WriteSealedState(const std::string& path, const std::string& kind, int version,
                      const std::string& body) {
  const std::string tmp = path + ".tmp";
  {
    std::ofstream out(tmp, std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write '" + tmp + "'");
    out << Header(kind, version, body.size(), Crc32(body.data(), body.size()));
    out.write(body.data(), static_cast<std::streamsize>(body.size()));
    out.flush();
    if (!out) throw std::runtime_error("write failed: '" + tmp + "'");
  }
  if (std::rename(tmp.c_str(), path.c_str()) != 0) {
    throw std::runtime_error("cannot replace '" + path + "'");
  }
}

StateFileRead ReadSealedState(const std::string& path, const std::string& kind, int version,
                              std::string* body) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return StateFileRead::kMissing;
  std::ostringstream all;
  all << in.rdbuf();
  std::string text = all.str();
  const auto fail = [&](const std::string& why) -> StateFileError {
    return StateFileError("state file '" + path + "' refused: " + why);
  };
  if (text.compare(0, sizeof(kPrefix) - 1, kPrefix) != 0) {
    *body = std::move(text);
    return StateFileRead::kUnsealed;
  }
  const size_t eol = text.find('\n');
  if (eol == std::string::npos || eol > 200) throw fail("header line unreadable");
  const std::string header = text.substr(0, eol);
  char file_kind[64] = {0};
  int file_version = 0;
  unsigned long long size = 0;
  unsigned int crc = 0;
  if (std::sscanf(header.c_str() + sizeof(kPrefix) - 1, "%63s v%d bytes %llu crc32 %8x", file_kind,
                  &file_version, &size, &crc) != 4) {
    throw fail("header line unreadable ('" + header + "')");
  }
  if (kind != file_kind) throw fail(std::string("a ") + file_kind + " file, not " + kind);
  if (file_version != version) {
    throw fail("version " + std::to_string(file_version) + ", this build reads version " +
               std::to_string(version));
  }
  const size_t have = text.size() - eol - 1;
  if (have != size) {
    throw fail("body of " + std::to_string(have) + " bytes, header says " + std::to_string(size) +
               " (truncated or appended to)");
  }
  const uint32_t actual = Crc32(text.data() + eol + 1, have);
  if (actual != crc) throw fail("checksum mismatch (the file is corrupt)");
  *body = text.substr(eol + 1);
  return StateFileRead::kSealed;
}

std::string SetAsideStateFile(const std::string& path) {
  const std::string aside = path + ".corrupt";
  return std::rename(path.c_str(), aside.c_str()) == 0 ? aside : "";
}

}  // namespace common
}  // namespace sarmap
