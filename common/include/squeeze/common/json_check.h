// squeeze::common — reading JSON configuration (scenes, plans) with errors that name the file and
// the key path: "scene.json: objects[2].material.k_volume: must be > 0, got -5".
//
//   nlohmann::json j = parse_json(text, "scene.json");   // NaN/Infinity literals kept, marked
//   JsonChecker c{"scene.json"};
//   c.keys(j, "planner", {"iterations", "seed"});        // unknown keys are errors
//   double t = c.positive(j["t_min"], "planner.t_min");
#pragma once
#include <Eigen/Core>
#include <Eigen/Geometry>
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace squeeze {

/// Parses JSON text. Bare NaN / Infinity literals (not JSON, but written by scripts) are kept as
/// marked strings so that validation can name their key. Throws InputError "FILE: invalid JSON: …".
nlohmann::json parse_json(const std::string& text, const std::string& file);

/// "a number", "an array", "NaN", … for messages.
std::string json_type_name(const nlohmann::json& j);
/// A number for messages (10 significant digits).
std::string format_number(double x);

/// Validation helpers; every failure throws InputError "FILE: PATH: problem".
struct JsonChecker {
  std::string file;
  [[noreturn]] void fail(const std::string& path, const std::string& problem) const;
  /// j must be an object whose keys are all in `allowed`.
  void keys(const nlohmann::json& j, const std::string& path, std::initializer_list<const char*> allowed) const;
  void keys(const nlohmann::json& j, const std::string& path, const std::vector<std::string>& allowed) const;
  double number(const nlohmann::json& j, const std::string& path) const;        // finite
  double positive(const nlohmann::json& j, const std::string& path) const;      // > 0
  double non_negative(const nlohmann::json& j, const std::string& path) const;  // >= 0
  /// An integer in [lo, hi].
  long long integer(const nlohmann::json& j, const std::string& path, long long lo, long long hi) const;
  Eigen::Vector3d vec3(const nlohmann::json& j, const std::string& path) const;
  bool boolean(const nlohmann::json& j, const std::string& path) const;
  std::string string(const nlohmann::json& j, const std::string& path) const;
  /// {"min": [x,y,z], "max": [x,y,z]} with min < max on every axis.
  Eigen::AlignedBox3d box(const nlohmann::json& j, const std::string& path) const;
};

}  // namespace squeeze
