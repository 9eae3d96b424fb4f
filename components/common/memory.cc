#include "common/memory.h"

#include <malloc.h>

#include <cstdlib>
#include <fstream>
#include <string>

namespace sarmap {
namespace common {

double ResidentMegabytes() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind("VmRSS:", 0) == 0) return std::atof(line.c_str() + 6) / 1024.0;
  return 0.0;
}

double HeapInUseMegabytes() {
  const struct mallinfo2 info = mallinfo2();
  return Megabytes(info.uordblks + info.hblkhd);
}

bool ReleaseFreeMemory() { return malloc_trim(0) != 0; }

}  // namespace common
}  // namespace sarmap
