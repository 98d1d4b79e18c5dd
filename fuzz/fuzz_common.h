// squeeze fuzzing harnesses (libFuzzer): the shared part. Each harness writes the fuzzer's bytes to
// a file in a private temporary folder (the readers take paths, as users give them) and calls one
// reader; an InputError is the expected answer to a bad input, anything else (a crash, a sanitizer
// report, another exception escaping, a hang, memory beyond -rss_limit_mb) is a finding.
#pragma once
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>

namespace squeeze::fuzz {

/// This process's scratch folder (created once, reused by every input).
inline const std::filesystem::path& scratch() {
  static const std::filesystem::path dir = [] {
    std::filesystem::path d = std::filesystem::temp_directory_path() / ("squeeze-fuzz-" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    return d;
  }();
  return dir;
}

/// Writes `size` bytes at `data` to scratch()/name and returns the path.
inline std::filesystem::path put(const std::string& name, const std::uint8_t* data, size_t size) {
  const std::filesystem::path p = scratch() / name;
  std::ofstream(p, std::ios::binary | std::ios::trunc).write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  return p;
}

}  // namespace squeeze::fuzz
