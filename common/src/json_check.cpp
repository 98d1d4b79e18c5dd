#include "squeeze/common/json_check.h"

#include <algorithm>
#include <cmath>
#include <vector>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "squeeze/common/error.h"

namespace squeeze {
using json = nlohmann::json;

namespace {

constexpr const char* kNonFinite = "\x01squeeze-non-finite:";  // marks NaN/Infinity literals

// JSON has no NaN or Infinity; scenes written by scripts sometimes contain them anyway. Replace
// such bare literals (outside strings), and numbers too large for a double (1e400: the parser
// would stop with "number overflow"), by a marked string so that validation can name the key.
// Also checks the nesting depth (at most kMaxJsonDepth): the parser would build it, but the
// document's destructor and copies recurse once per level, so 200,000 levels overflow the stack.
constexpr int kMaxJsonDepth = 256;
std::string mark_non_finite(const std::string& text, const std::string& file) {
  std::string out;
  out.reserve(text.size());
  bool in_string = false;
  int depth = 0;
  for (size_t i = 0; i < text.size(); ++i) {
    const char c = text[i];
    if (in_string) {
      out += c;
      if (c == '\\' && i + 1 < text.size()) out += text[++i];
      else if (c == '"') in_string = false;
      continue;
    }
    if (c == '"') {
      in_string = true;
      out += c;
      continue;
    }
    if (c == '[' || c == '{') {
      if (++depth > kMaxJsonDepth)
        throw InputError(file + ": invalid JSON: nested more than " + std::to_string(kMaxJsonDepth) + " levels deep");
    } else if (c == ']' || c == '}') {
      --depth;
    }
    const bool boundary_before = i == 0 || !std::isalnum(static_cast<unsigned char>(text[i - 1]));
    if (boundary_before && (c == '-' || std::isdigit(static_cast<unsigned char>(c)))) {
      // A number: its characters as the JSON grammar allows them; marked if it overflows a double.
      size_t n = 0;
      while (i + n < text.size() && (std::isdigit(static_cast<unsigned char>(text[i + n])) ||
                                     std::strchr("+-.eE", text[i + n])))
        ++n;
      const std::string number = text.substr(i, n);
      char* end = nullptr;
      const double x = std::strtod(number.c_str(), &end);
      if (n > 0 && end == number.c_str() + n && std::isinf(x)) {
        out += '"';
        out += "\\u0001squeeze-non-finite:";
        out += number;
        out += '"';
        i += n - 1;
        continue;
      }
    }
    bool replaced = false;
    for (const char* lit : {"-Infinity", "+Infinity", "Infinity", "-NaN", "NaN", "-nan", "nan", "-inf", "inf"}) {
      const size_t n = std::char_traits<char>::length(lit);
      const bool boundary_after = i + n >= text.size() || !std::isalnum(static_cast<unsigned char>(text[i + n]));
      if (boundary_before && boundary_after && text.compare(i, n, lit) == 0) {
        out += '"';
        out += "\\u0001squeeze-non-finite:";
        out += lit;
        out += '"';
        i += n - 1;
        replaced = true;
        break;
      }
    }
    if (!replaced) out += c;
  }
  return out;
}

// Where the parser is in the document, for naming a duplicate key: per open object or array, the
// current key or element index.
struct JsonPath {
  struct Level {
    bool array = false;
    long index = -1;           // arrays: the element being read
    std::string key;           // objects: the key being read
    std::vector<std::string> keys;  // objects: the keys seen
  };
  std::vector<Level> levels;
  std::string str() const {
    std::string p;
    for (const Level& l : levels)
      if (l.array) p += "[" + std::to_string(std::max(0L, l.index)) + "]";
      else if (!l.key.empty()) p += (p.empty() ? "" : ".") + l.key;
    return p;
  }
  void element() {  // a value starts (or an object or array) inside the current level
    if (!levels.empty() && levels.back().array) ++levels.back().index;
  }
};
}  // namespace

std::string json_type_name(const json& j) {
  if (j.is_string() && j.get_ref<const std::string&>().rfind(kNonFinite, 0) == 0)
    return j.get_ref<const std::string&>().substr(std::char_traits<char>::length(kNonFinite));
  if (j.is_null()) return "null";
  if (j.is_boolean()) return "a boolean";
  if (j.is_number()) return "a number";
  if (j.is_string()) return "a string";
  if (j.is_array()) return "an array";
  return "an object";
}

std::string format_number(double x) {
  std::ostringstream s;
  s << std::setprecision(10) << x;
  return s.str();
}


json parse_json(const std::string& text, const std::string& file) {
  const std::string marked = mark_non_finite(text, file);
  JsonPath path;
  // Duplicate keys are an error (the parser would keep the last one silently).
  const json::parser_callback_t check = [&](int, json::parse_event_t event, json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
      case json::parse_event_t::array_start:
        path.element();
        path.levels.push_back({event == json::parse_event_t::array_start, -1, {}, {}});
        break;
      case json::parse_event_t::key: {
        JsonPath::Level& l = path.levels.back();
        l.key = parsed.get<std::string>();
        if (std::find(l.keys.begin(), l.keys.end(), l.key) != l.keys.end())
          throw InputError(file + ": " + path.str() + ": duplicate key (each key may appear once in an object)");
        l.keys.push_back(l.key);
        break;
      }
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        if (!path.levels.empty()) path.levels.pop_back();
        break;
      case json::parse_event_t::value:
        path.element();
        break;
    }
    return true;
  };
  try {
    return json::parse(marked, check);
  } catch (const json::exception& e) {  // parse errors; anything else the parser reports
    std::string what = e.what();
    const auto pos = what.find("] ");
    if (pos != std::string::npos) what = what.substr(pos + 2);
    throw InputError(file + ": invalid JSON: " + what);
  }
}

void JsonChecker::fail(const std::string& path, const std::string& problem) const {
  throw InputError(file + ": " + path + ": " + problem);
}
void JsonChecker::keys(const json& j, const std::string& path, std::initializer_list<const char*> allowed) const {
  keys(j, path, std::vector<std::string>(allowed.begin(), allowed.end()));
}
void JsonChecker::keys(const json& j, const std::string& path, const std::vector<std::string>& allowed) const {
  if (!j.is_object()) fail(path.empty() ? "(top level)" : path, "must be an object, got " + json_type_name(j));
  for (auto it = j.begin(); it != j.end(); ++it) {
    bool ok = false;
    for (const std::string& a : allowed) ok = ok || it.key() == a;
    if (!ok) {
      std::string list;
      for (const std::string& a : allowed) list += (list.empty() ? "" : ", ") + a;
      fail(path.empty() ? it.key() : path + "." + it.key(), "unknown key (allowed here: " + list + ")");
    }
  }
}
double JsonChecker::number(const json& j, const std::string& path) const {
  if (!j.is_number()) {
    if (j.is_string() && j.get_ref<const std::string&>().rfind(kNonFinite, 0) == 0)
      fail(path, "must be a finite number, got " + json_type_name(j));
    fail(path, "must be a number, got " + json_type_name(j));
  }
  const double x = j.get<double>();
  if (!std::isfinite(x)) fail(path, "must be a finite number");
  return x;
}
double JsonChecker::positive(const json& j, const std::string& path) const {
  const double x = number(j, path);
  if (!(x > 0)) fail(path, "must be > 0, got " + format_number(x));
  return x;
}
double JsonChecker::non_negative(const json& j, const std::string& path) const {
  const double x = number(j, path);
  if (x < 0) fail(path, "must be >= 0, got " + format_number(x));
  return x;
}
Eigen::Vector3d JsonChecker::vec3(const json& j, const std::string& path) const {
  if (!j.is_array() || j.size() != 3) fail(path, "must be an array of 3 numbers, got " + json_type_name(j) +
                                                     (j.is_array() ? " of " + std::to_string(j.size()) : ""));
  Eigen::Vector3d v;
  for (int k = 0; k < 3; ++k) v(k) = number(j[k], path + "[" + std::to_string(k) + "]");
  return v;
}
bool JsonChecker::boolean(const json& j, const std::string& path) const {
  if (!j.is_boolean()) fail(path, "must be true or false, got " + json_type_name(j));
  return j.get<bool>();
}
std::string JsonChecker::string(const json& j, const std::string& path) const {
  if (!j.is_string() || j.get_ref<const std::string&>().rfind(kNonFinite, 0) == 0)
    fail(path, "must be a string, got " + json_type_name(j));
  return j.get<std::string>();
}
Eigen::AlignedBox3d JsonChecker::box(const json& j, const std::string& path) const {
  keys(j, path, {"min", "max"});
  if (!j.contains("min")) fail(path + ".min", "missing (required)");
  if (!j.contains("max")) fail(path + ".max", "missing (required)");
  const Eigen::Vector3d lo = vec3(j["min"], path + ".min"), hi = vec3(j["max"], path + ".max");
  if (!(lo.array() < hi.array()).all()) fail(path, "min must be below max on every axis");
  return {lo, hi};
}

long long JsonChecker::integer(const json& j, const std::string& path, long long lo, long long hi) const {
  const double x = number(j, path);
  if (x != std::floor(x) || x < static_cast<double>(lo) || x > static_cast<double>(hi))
    fail(path, "must be an integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "], got " + format_number(x));
  return static_cast<long long>(x);
}

}  // namespace squeeze
