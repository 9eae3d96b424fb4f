#include "common/state_file.h"

#include <zlib.h>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace sarmap {
namespace common {
namespace {

// Of one length for a kind and version, whatever the size and checksum.
std::string Header(const std::string& kind, int version, uint64_t size, uint32_t crc) {
  char fields[64];
  std::snprintf(fields, sizeof(fields), "bytes %020llu crc32 %08x\n",
                static_cast<unsigned long long>(size), crc);
  return "# sarmap-state " + kind + " v" + std::to_string(version) + " " + fields;
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

// Buffers the body, and on each flush adds the bytes to the checksum and writes them out.
class SealedStateWriter::ChecksumBuffer : public std::streambuf {
 public:
  explicit ChecksumBuffer(std::FILE* file) : file_(file) { setp(buffer_, buffer_ + kSize); }
  uint32_t crc() const { return crc_; }
  uint64_t size() const { return size_; }
  bool ok() const { return ok_; }

 protected:
  int_type overflow(int_type c) override {
    if (!Flush()) return traits_type::eof();
    if (!traits_type::eq_int_type(c, traits_type::eof())) {
      *pptr() = traits_type::to_char_type(c);
      pbump(1);
    }
    return traits_type::not_eof(c);
  }
  // A large block (a submap's grid) goes out directly, not through the buffer.
  std::streamsize xsputn(const char* data, std::streamsize n) override {
    if (n < static_cast<std::streamsize>(kSize) / 2) return std::streambuf::xsputn(data, n);
    if (!Flush() || !Write(data, static_cast<size_t>(n))) return 0;
    return n;
  }
  int sync() override { return Flush() ? 0 : -1; }

 private:
  static constexpr size_t kSize = 1 << 16;
  bool Write(const char* data, size_t n) {
    crc_ = Crc32(data, n, crc_);
    size_ += n;
    ok_ = ok_ && std::fwrite(data, 1, n, file_) == n;
    return ok_;
  }
  bool Flush() {
    const size_t n = static_cast<size_t>(pptr() - pbase());
    setp(buffer_, buffer_ + kSize);
    return Write(buffer_, n);
  }
  std::FILE* file_;
  char buffer_[kSize];
  uint32_t crc_ = 0;
  uint64_t size_ = 0;
  bool ok_ = true;
};

SealedStateWriter::SealedStateWriter(const std::string& path, const std::string& kind, int version)
    : path_(path), tmp_(path + ".tmp"), kind_(kind), version_(version) {
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) throw std::runtime_error("cannot write '" + tmp_ + "'");
  // The header's place; its fields are known at Commit().
  const std::string placeholder = Header(kind_, version_, 0, 0);
  if (std::fwrite(placeholder.data(), 1, placeholder.size(), file_) != placeholder.size()) {
    std::fclose(file_);
    std::remove(tmp_.c_str());
    throw std::runtime_error("write failed: '" + tmp_ + "'");
  }
  buffer_ = std::make_unique<ChecksumBuffer>(file_);
  body_ = std::make_unique<std::ostream>(buffer_.get());
}

SealedStateWriter::~SealedStateWriter() {
  if (file_) std::fclose(file_);
  if (!committed_) std::remove(tmp_.c_str());
}

void SealedStateWriter::Commit() {
  body_->flush();
  const std::string header = Header(kind_, version_, buffer_->size(), buffer_->crc());
  bool ok = *body_ && buffer_->ok() && std::fseek(file_, 0, SEEK_SET) == 0 &&
            std::fwrite(header.data(), 1, header.size(), file_) == header.size();
  ok = std::fclose(file_) == 0 && ok;
  file_ = nullptr;
  if (!ok) throw std::runtime_error("write failed: '" + tmp_ + "'");
  if (std::rename(tmp_.c_str(), path_.c_str()) != 0) {
    throw std::runtime_error("cannot replace '" + path_ + "'");
  }
  committed_ = true;
}

void WriteSealedState(const std::string& path, const std::string& kind, int version,
                      const std::string& body) {
  SealedStateWriter writer(path, kind, version);
  writer.body().write(body.data(), static_cast<std::streamsize>(body.size()));
  writer.Commit();
}

StateFileRead ReadSealedState(const std::string& path, const std::string& kind, int version,
                              std::string* body) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return StateFileRead::kMissing;
  const auto fail = [&](const std::string& why) -> StateFileError {
    return StateFileError("state file '" + path + "' refused: " + why);
  };
  // The body is read once, straight into *body (a large file is not copied on the way).
  in.seekg(0, std::ios::end);
  const std::streamoff file_size = in.tellg();
  in.seekg(0, std::ios::beg);
  if (file_size < 0 || !in) throw fail("cannot be read");
  const auto read_into = [&](std::streamoff from, std::streamoff size, std::string* out) {
    out->assign(static_cast<size_t>(size), '\0');
    in.seekg(from, std::ios::beg);
    if (size > 0) in.read(&(*out)[0], size);
    if (!in) throw fail("cannot be read");
  };
  std::string head;
  read_into(0, std::min<std::streamoff>(file_size, 256), &head);
  if (head.compare(0, sizeof(kPrefix) - 1, kPrefix) != 0) {
    read_into(0, file_size, body);
    return StateFileRead::kUnsealed;
  }
  const size_t eol = head.find('\n');
  if (eol == std::string::npos || eol > 200) throw fail("header line unreadable");
  const std::string header = head.substr(0, eol);
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
  const std::streamoff have = file_size - static_cast<std::streamoff>(eol) - 1;
  if (static_cast<unsigned long long>(have) != size) {
    throw fail("body of " + std::to_string(have) + " bytes, header says " + std::to_string(size) +
               " (truncated or appended to)");
  }
  read_into(static_cast<std::streamoff>(eol) + 1, have, body);
  if (Crc32(body->data(), body->size()) != crc) {
    body->clear();
    throw fail("checksum mismatch (the file is corrupt)");
  }
  return StateFileRead::kSealed;
}

std::string SetAsideStateFile(const std::string& path) {
  const std::string aside = path + ".corrupt";
  return std::rename(path.c_str(), aside.c_str()) == 0 ? aside : "";
}

}  // namespace common
}  // namespace sarmap
