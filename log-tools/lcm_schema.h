#pragma once
// LCM type definitions read at run time: a parser of the .lcm language (package, struct,
// primitive and struct members, fixed and variable, multi-dimensional arrays, const
// declarations, comments) and each struct's fingerprint, computed the way lcm-gen computes it,
// so any message can be recognised by its first 8 bytes without generated code. No LCM
// dependency.
//
// Fingerprint (lcm-gen, lcmgen.c and the _computeHash of the generated code):
//   base = 0x12345678, then for each member in order: its name; its type name when the type
//   is primitive (a struct's name is left out so renaming it keeps the fingerprint); the
//   number of dimensions; for each dimension its mode (0 fixed, 1 variable) and its size text
//   ("3" or the member that holds the count). A string s enters as strlen(s) and then each
//   character, each through  v = ((v << 8) ^ (v >> 55)) + c  (arithmetic shift, signed char).
//   fingerprint(T) = rotl1(base(T) + sum of fingerprint(S) over the struct-typed members S of
//   T, one term per member), where a type already being expanded contributes 0.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace sarmap {
namespace logtools {

struct LcmDimension {
  bool variable = false;  // the count is the value of the member `size` (else a number)
  std::string size;
};

struct LcmMember {
  std::string type;  // a primitive name or a fully qualified struct name ("pkg.name_t")
  std::string name;
  std::vector<LcmDimension> dims;
  std::string comment;  // the comment on the member's line, if any
  int line = 0;
};

struct LcmConstant {
  std::string type;
  std::string name;
  std::string value;  // as written
};

struct LcmStruct {
  std::string package;
  std::string name;  // short name
  std::vector<LcmMember> members;
  std::vector<LcmConstant> constants;
  std::string file;
  int line = 0;
  int64_t base_hash = 0;
  uint64_t fingerprint = 0;  // filled by LcmTypeSet::Resolve
  std::string full_name() const { return package.empty() ? name : package + "." + name; }
};

bool IsLcmPrimitive(const std::string& type);
// Bytes of a fixed-size primitive on the wire; 0 for string.
int LcmPrimitiveBytes(const std::string& type);

// Parses the text of one .lcm file. Appends its structs to *out; returns false with
// "file:line: what" in *error on the first mistake.
bool ParseLcm(const std::string& text, const std::string& file, std::vector<LcmStruct>* out,
              std::string* error);

// lcm-gen's hash of one struct's own declaration (without nested types).
int64_t LcmBaseHash(const LcmStruct& s);

class LcmTypeSet {
 public:
  // Parses every *.lcm in `dir` (sorted by name). Returns false with the problems in *errors
  // (all files are read; every problem is listed).
  bool AddDirectory(const std::string& dir, std::vector<std::string>* errors);
  bool AddText(const std::string& text, const std::string& file, std::vector<std::string>* errors);
  // Checks that every struct member names a known type, every variable dimension an earlier
  // integer member of the same struct, and computes every fingerprint.
  bool Resolve(std::vector<std::string>* errors);

  // nullptr when unknown.
  const LcmStruct* Find(const std::string& full_name) const;
  const LcmStruct* FindByFingerprint(uint64_t fingerprint) const;
  const std::map<std::string, LcmStruct>& structs() const { return structs_; }
  // Types that share a fingerprint with another (the one that sorts first by name decodes),
  // found by Resolve.
  const std::vector<std::string>& ambiguities() const { return ambiguities_; }
  // Fewest bytes one encoded struct takes (no fingerprint): variable arrays empty, strings
  // empty. Valid after Resolve.
  uint64_t MinWireSize(const std::string& full_name) const;

 private:
  uint64_t Fingerprint(const std::string& full_name, std::vector<std::string>* stack) const;
  uint64_t ComputeMinWireSize(const std::string& full_name, std::vector<std::string>* stack);

  std::map<std::string, LcmStruct> structs_;  // by full name
  std::map<uint64_t, std::string> by_fingerprint_;
  std::map<std::string, uint64_t> min_wire_size_;
  std::vector<std::string> ambiguities_;
};

}  // namespace logtools
}  // namespace sarmap
