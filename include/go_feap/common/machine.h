// What the machine the code runs on has.
#pragma once

#include <unistd.h>

#include <limits>

namespace go_feap::common {

/// Bytes of physical memory (sysconf); +inf when the system does not say.
inline double physicalMemoryBytes() {
  const long pages = ::sysconf(_SC_PHYS_PAGES), page = ::sysconf(_SC_PAGE_SIZE);
  if (pages <= 0 || page <= 0) return std::numeric_limits<double>::infinity();
  return static_cast<double>(pages) * static_cast<double>(page);
}

}  // namespace go_feap::common
