#include "squeeze/render/exporter.h"

#include <cstdio>

namespace squeeze::render {

std::string frame_file_name(const std::string& prefix, int k, const std::string& extension) {
  char digits[16];
  std::snprintf(digits, sizeof digits, "%05d", k);
  return prefix + digits + extension;
}

}  // namespace squeeze::render
