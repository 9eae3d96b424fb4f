#pragma once
// Little-endian binary state files (SLAM's pose graph, the sound map): plain values, counted
// sequences and Eigen arrays written field by field, read back with bounds and truncation checks.
// The files themselves are sealed and replaced atomically by common::SealedStateWriter
// (state_file.h).

#include <Eigen/Core>
#include <cstdint>
#include <fstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

namespace sarmap {
namespace common {

class BinaryWriter {
 public:
  explicit BinaryWriter(std::ostream* out) : out_(out) {}
  template <class T>
  void Pod(const T& v) {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    out_->write(reinterpret_cast<const char*>(&v), sizeof(T));
  }
  void String(const std::string& s) {
    Pod<int64_t>(static_cast<int64_t>(s.size()));
    out_->write(s.data(), static_cast<std::streamsize>(s.size()));
  }
  // A counted sequence of plain values (bytes as in memory: numbers, fixed-size Eigen vectors),
  // written as one block.
  template <class T>
  void Array(const std::vector<T>& v) {
    Pod<int64_t>(static_cast<int64_t>(v.size()));
    out_->write(reinterpret_cast<const char*>(v.data()),
                static_cast<std::streamsize>(v.size() * sizeof(T)));
  }
  template <class Derived>
  void Matrix(const Eigen::DenseBase<Derived>& m) {
    Pod<int64_t>(m.rows());
    Pod<int64_t>(m.cols());
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      for (Eigen::Index r = 0; r < m.rows(); ++r) Pod<double>(static_cast<double>(m(r, c)));
  }

 private:
  std::ostream* out_;
};

// Reads bytes held elsewhere (a state file's body) as a stream, without copying them:
//   MemoryStreamBuffer buffer(body.data(), body.size()); std::istream in(&buffer);
// The bytes must outlive it.
class MemoryStreamBuffer : public std::streambuf {
 public:
  MemoryStreamBuffer(const char* data, size_t size) {
    char* begin = const_cast<char*>(data);  // only ever read
    setg(begin, begin, begin + size);
  }
};

class BinaryReader {
 public:
  // what: names the file in errors ("pose-graph file", "sound-map state").
  BinaryReader(std::istream* in, std::string what) : in_(in), what_(std::move(what)) {}
  template <class T>
  T Pod() {
    static_assert(std::is_trivially_copyable<T>::value, "plain values only");
    T v;
    in_->read(reinterpret_cast<char*>(&v), sizeof(T));
    if (!*in_) throw std::runtime_error(what_ + " truncated");
    return v;
  }
  // A count written with Pod<int64_t>, at most max.
  int64_t Count(int64_t max) {
    const int64_t n = Pod<int64_t>();
    if (n < 0 || n > max) throw std::runtime_error(what_ + " corrupt (bad count)");
    return n;
  }
  std::string String(int64_t max_length = 1 << 20) {
    std::string s(static_cast<size_t>(Count(max_length)), '\0');
    in_->read(&s[0], static_cast<std::streamsize>(s.size()));
    if (!*in_) throw std::runtime_error(what_ + " truncated");
    return s;
  }
  // What BinaryWriter::Array wrote, at most max_count values.
  template <class T>
  std::vector<T> Array(int64_t max_count) {
    std::vector<T> v(static_cast<size_t>(Count(max_count)));
    in_->read(reinterpret_cast<char*>(v.data()),
              static_cast<std::streamsize>(v.size() * sizeof(T)));
    if (!*in_) throw std::runtime_error(what_ + " truncated");
    return v;
  }
  Eigen::MatrixXd Matrix(int64_t max_elements = 1 << 26) {
    const int64_t rows = Count(max_elements), cols = Count(max_elements);
    if (rows * cols > max_elements) throw std::runtime_error(what_ + " corrupt (matrix size)");
    Eigen::MatrixXd m(rows, cols);
    for (int64_t c = 0; c < cols; ++c)
      for (int64_t r = 0; r < rows; ++r) m(r, c) = Pod<double>();
    return m;
  }
  [[noreturn]] void Corrupt(const std::string& why) const {
    throw std::runtime_error(what_ + " corrupt (" + why + ")");
  }

 private:
  std::istream* in_;
  std::string what_;
};

}  // namespace common
}  // namespace sarmap
