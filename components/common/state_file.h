#pragma once
// Sealed state files: what a node saves to resume after a restart (SLAM's pose graph, the
// people map), with a version and a checksum, so that a truncated, bit-flipped or foreign file
// is refused with a clear reason instead of resumed silently or crashing the node.
//
// The file is one ASCII header line, then the body as given (binary or text):
//   # sarmap-state <kind> v<version> bytes <body size> crc32 <8 hex digits>\n
// (the "# " keeps a YAML body a valid YAML file). Written to PATH.tmp, then renamed over PATH.
// The writer pads the size with zeros to 20 digits, so the header has its final length before
// the body is known (the body streams to disk; see SealedStateWriter).

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <ostream>
#include <stdexcept>
#include <string>

namespace sarmap {
namespace common {

// CRC-32 (IEEE 802.3, as zlib's crc32): Crc32("123456789") == 0xCBF43926. `crc` continues a
// previous result.
uint32_t Crc32(const void* data, size_t size, uint32_t crc = 0);

class StateFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

void WriteSealedState(const std::string& path, const std::string& kind, int version,
                      const std::string& body);

// Writes a sealed state file as its body is produced: body() streams to PATH.tmp through the
// checksum, so a large body (SLAM's pose graph: tens of MB) is never held in memory whole.
// Commit() fills in the header and renames PATH.tmp over PATH; a writer destroyed without
// Commit() (an exception while writing) removes PATH.tmp and leaves PATH as it was.
class SealedStateWriter {
 public:
  // Throws std::runtime_error when PATH.tmp cannot be created.
  SealedStateWriter(const std::string& path, const std::string& kind, int version);
  ~SealedStateWriter();
  SealedStateWriter(const SealedStateWriter&) = delete;
  SealedStateWriter& operator=(const SealedStateWriter&) = delete;

  std::ostream& body() { return *body_; }
  // Throws std::runtime_error on any write failure (PATH is then left as it was).
  void Commit();

 private:
  class ChecksumBuffer;
  std::string path_, tmp_, kind_;
  int version_;
  std::FILE* file_ = nullptr;
  std::unique_ptr<ChecksumBuffer> buffer_;
  std::unique_ptr<std::ostream> body_;
  bool committed_ = false;
};

enum class StateFileRead {
  kMissing,   // no file: nothing to resume
  kSealed,    // header, version and checksum verified
  kUnsealed,  // no header (a file written before state files were sealed): body is the whole file
};

// Reads `path` into *body. Throws StateFileError (naming the file and what is wrong) when the
// header names another kind or version, or the size or checksum do not match.
StateFileRead ReadSealedState(const std::string& path, const std::string& kind, int version,
                              std::string* body);

// Moves a refused state file aside to PATH.corrupt (kept for inspection; the next save writes
// a fresh PATH). Returns the new name, or "" when it could not be moved.
std::string SetAsideStateFile(const std::string& path);

}  // namespace common
}  // namespace sarmap
