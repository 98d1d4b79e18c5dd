#include "squeeze/meshing/surface_io.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <fcntl.h>
#include <sys/types.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <functional>
#include <fstream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <unordered_map>
#include <vector>

#include <spdlog/spdlog.h>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/triangulate_polygon.h"

namespace squeeze::meshing {
namespace fs = std::filesystem;

namespace {

struct KeyHash {
  size_t operator()(const std::array<double, 3>& k) const {
    size_t h = 0;
    for (double d : k) {
      if (d == 0.0) d = 0.0;  // -0 == +0
      h ^= std::hash<double>()(d) + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2);
    }
    return h;
  }
};

std::string lower(std::string s) {
  std::transform(s.begin(), s.end(), s.begin(), [](unsigned char c) { return std::tolower(c); });
  return s;
}

// Walks the node tree, applying accumulated transforms, and appends the triangles of every mesh.
// Checks what assimp hands over before using it (mesh and vertex indices, counts that would not
// fit an int, node depth): a broken file is an InputError naming `name`, never a crash.
void collect(const std::string& name, const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent,
             std::vector<std::array<double, 3>>& pts, std::vector<std::array<int, 3>>& tris, int depth = 0) {
  if (depth > 1000) throw InputError(name + ": scene graph nested more than 1000 deep");
  const aiMatrix4x4 m = parent * node->mTransformation;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    if (node->mMeshes[k] >= scene->mNumMeshes) throw InputError(name + ": a node refers to a mesh that does not exist");
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
    if (pts.size() + mesh->mNumVertices > static_cast<size_t>(std::numeric_limits<int>::max()))
      throw InputError(name + ": more than 2^31 vertices");
    const int base = static_cast<int>(pts.size());
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D p = m * mesh->mVertices[i];
      pts.push_back({p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      for (unsigned j = 0; j < face.mNumIndices; ++j)
        if (face.mIndices[j] >= mesh->mNumVertices)
          throw InputError(name + ": face " + std::to_string(f) + " refers to vertex " + std::to_string(face.mIndices[j]) +
                           " of " + std::to_string(mesh->mNumVertices));
      for (unsigned j = 2; j < face.mNumIndices; ++j)  // polygons as fans; points and lines dropped
        tris.push_back({base + static_cast<int>(face.mIndices[0]),
                        base + static_cast<int>(face.mIndices[j - 1]),
                        base + static_cast<int>(face.mIndices[j])});
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) collect(name, scene, node->mChildren[c], m, pts, tris, depth + 1);
}

// OBJ in file order (assimp duplicates OBJ vertices per face corner): `v` and `f` lines only;
// f tokens are i, i/t, i//n or i/t/n, 1-based or negative (relative); polygons become fans. A
// backslash ending a line continues it on the next (the OBJ format's line continuation: trimesh's
// test model wallhole.obj writes its long faces so; errors name the statement's first line).
void read_obj_in_order(const fs::path& path, std::vector<std::array<double, 3>>& pts,
                       std::vector<std::array<int, 3>>& tris) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot open for reading");
  std::string line;
  std::vector<long> poly;
  std::vector<long> face_line;  // line of each triangle, for the range check
  long lineno = 0, read = 0;
  // Whether `line` ends with a backslash (a \r and blanks after it allowed); it is then dropped.
  auto continues = [](std::string& l) {
    size_t end = l.size();
    while (end > 0 && (l[end - 1] == '\r' || l[end - 1] == ' ' || l[end - 1] == '\t')) --end;
    if (end == 0 || l[end - 1] != '\\') return false;
    l.resize(end - 1);
    return true;
  };
  while (std::getline(in, line)) {
    lineno = ++read;
    for (std::string next; continues(line) && std::getline(in, next); ++read) line += ' ' + next;
    if (line.size() < 2 || (line[1] != ' ' && line[1] != '\t')) continue;
    if (line[0] == 'v') {
      std::array<double, 3> p{};
      char* cur = line.data() + 1;
      for (double& d : p) {
        char* end = nullptr;
        d = std::strtod(cur, &end);
        if (end == cur) throw InputError(name + ": line " + std::to_string(lineno) + ": malformed vertex");
        cur = end;
      }
      pts.push_back(p);
    } else if (line[0] == 'f') {
      poly.clear();
      const char* cur = line.c_str() + 1;
      while (true) {
        while (*cur == ' ' || *cur == '\t' || *cur == '\r') ++cur;
        if (!*cur) break;
        char* end = nullptr;
        long i = std::strtol(cur, &end, 10);
        if (end == cur || i == 0)
          throw InputError(name + ": line " + std::to_string(lineno) + ": malformed face");
        poly.push_back(i < 0 ? static_cast<long>(pts.size()) + i : i - 1);
        cur = end;
        while (*cur && *cur != ' ' && *cur != '\t' && *cur != '\r') ++cur;  // skip /t/n
      }
      for (long v : poly)
        if (v < 0 || v >= (1L << 31) - 1)
          throw InputError(name + ": line " + std::to_string(lineno) + ": vertex index out of range");
      triangulate_polygon(pts, poly, tris);
      face_line.resize(tris.size(), lineno);
    }
  }
  for (size_t t = 0; t < tris.size(); ++t)
    for (int v : tris[t])
      if (v >= static_cast<int>(pts.size()))
        throw InputError(name + ": line " + std::to_string(face_line[t]) + ": vertex index " + std::to_string(v + 1) +
                         " out of range (" + std::to_string(pts.size()) + " vertices)");
}

// Checks a PLY file before assimp reads it, since assimp 5.2 loops forever on a header without
// end_header, reads past truncated data, and allocates whatever a corrupt list count asks for
// (fuzz_surface found each). The header must be strict: printable ASCII, known keywords, each line
// with exactly its fields, known types, element counts below 2^31. Then the whole body is walked as
// the header describes it: ASCII, one item per line with one token per scalar and, for a list, a
// non-negative whole count followed by that many tokens; binary, every list count read (in the
// file's byte order) and its items found within the file. Throws InputError naming the line or item.
// Once the header is read, `visitor_for` (where given) is asked, with the elements' names and their
// properties' names in order, for a visitor; one that it returns is called with every value of the
// body in file order: (element index, item, property index, position in the list or -1 for a
// scalar, value).
using PlyVisitor = std::function<void(size_t element, long long item, size_t property, long long at, double value)>;
using PlyLayout = std::vector<std::pair<std::string, std::vector<std::string>>>;
void check_ply(const fs::path& path, const std::function<PlyVisitor(const PlyLayout&)>& visitor_for = nullptr) {
  const std::string name = path.string();
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(name + ": cannot open for reading");
  std::string line;
  if (!std::getline(in, line) || (line != "ply" && line != "ply\r")) throw InputError(name + ": not a PLY file (no 'ply' line)");
  struct Property {
    bool list = false;
    int count_size = 0;  // bytes of a list's count (binary)
    int size = 0;        // bytes of the scalar or of each list item (binary)
    std::string type;    // of the scalar or of each list item
    std::string name;
  };
  struct Element {
    std::string name;
    long long count = 0;
    std::vector<Property> properties;
  };
  std::vector<Element> elements;
  bool ascii = true, big_endian = false, format = false, ended = false;
  int lines = 1;
  std::vector<std::string> skipped;  // header lines of text without a keyword
  const auto bad = [&](const std::string& what) {
    throw InputError(name + ": PLY header line " + std::to_string(lines) + ": " + what);
  };
  const auto size_of = [&](const std::string& t) -> int {
    if (t == "char" || t == "uchar" || t == "int8" || t == "uint8") return 1;
    if (t == "short" || t == "ushort" || t == "int16" || t == "uint16") return 2;
    if (t == "int" || t == "uint" || t == "float" || t == "int32" || t == "uint32" || t == "float32") return 4;
    if (t == "double" || t == "float64") return 8;
    bad("unknown property type '" + t + "'");
    return 0;
  };
  while (std::getline(in, line)) {
    ++lines;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (lines > 10000 || in.tellg() > (1 << 20)) break;
    for (unsigned char c : line)
      if (c != ' ' && c != '\t' && (c < 0x21 || c > 0x7e)) bad("holds a control or non-ASCII byte");
    std::istringstream ss(line);
    std::string kw;
    ss >> kw;
    std::vector<std::string> f;
    for (std::string t; ss >> t;) f.push_back(t);
    if (kw == "comment" || kw == "obj_info") continue;
    if (kw == "end_header") {
      if (!f.empty()) bad("end_header followed by more text");
      ended = true;
      break;
    }
    if (kw == "format") {
      if (f.size() != 2) bad("a format line is 'format TYPE VERSION'");
      if (f[0] != "ascii" && f[0] != "binary_little_endian" && f[0] != "binary_big_endian")
        throw InputError(name + ": PLY header: unknown format '" + f[0] + "'");
      ascii = f[0] == "ascii";
      big_endian = f[0] == "binary_big_endian";
      format = true;
    } else if (kw == "element") {
      if (f.size() != 2) bad("an element line is 'element NAME COUNT'");
      char* end = nullptr;
      const double count = std::strtod(f[1].c_str(), &end);
      if (*end || !(count >= 0) || count != std::floor(count) || count > std::numeric_limits<int>::max())
        throw InputError(name + ": PLY header: element " + f[0] + " has count '" + f[1] + "' (a whole number below 2^31 expected)");
      elements.push_back({f[0], static_cast<long long>(count), {}});
    } else if (kw == "property") {
      if (elements.empty()) bad("a property before any element");
      Property prop;
      prop.list = !f.empty() && f[0] == "list";
      if (!f.empty()) prop.name = f.back();
      if (f.size() != (prop.list ? 4u : 2u))
        bad("a property line is 'property TYPE NAME' or 'property list COUNT_TYPE ITEM_TYPE NAME'");
      if (prop.list) {
        prop.count_size = size_of(f[1]);
        if (f[1].find("float") != std::string::npos || f[1] == "double") bad("a list count of type " + f[1]);
        prop.size = size_of(f[2]);
        prop.type = f[2];
      } else {
        prop.size = size_of(f[0]);
        prop.type = f[0];
      }
      elements.back().properties.push_back(prop);
    } else if (kw.empty()) {
      continue;  // (a blank line)
    } else {
      // A line with no keyword is text some exporters write without 'comment' (Blender 2.4x:
      // "Created by Blender3D 247 - www.blender.org, source file: ..."); readers skip it, so
      // does this one, and says so once the header is whole (a truncated header's last line is
      // no text line).
      skipped.push_back("PLY header line " + std::to_string(lines) + " has no keyword ('" +
                        (line.size() > 60 ? line.substr(0, 60) + "..." : line) + "'): skipped as a comment");
    }
  }
  if (!ended) throw InputError(name + ": PLY header has no end_header line (truncated?)");
  for (const std::string& w : skipped) spdlog::warn("{}: {}", name, w);
  if (!format) throw InputError(name + ": PLY header has no format line");
  PlyVisitor visit;
  if (visitor_for) {
    PlyLayout layout;
    for (const Element& e : elements) {
      layout.emplace_back(e.name, std::vector<std::string>{});
      for (const Property& prop : e.properties) layout.back().second.push_back(prop.name);
    }
    visit = visitor_for(layout);
  }

  const auto truncated = [&](const Element& e, long long item, const std::string& what) {
    throw InputError(name + ": PLY " + e.name + " " + std::to_string(item) + ": " + what);
  };
  if (ascii) {
    long long lineno = lines;
    for (size_t ei = 0; ei < elements.size(); ++ei) {
      const Element& e = elements[ei];
      for (long long item = 0; item < e.count; ++item) {
        do {
          if (!std::getline(in, line))
            truncated(e, item, "missing: the header announces " + std::to_string(e.count) + " (truncated?)");
          ++lineno;
        } while (line.find_first_not_of(" \t\r") == std::string::npos);
        std::istringstream ss(line);
        std::vector<std::string> tok;
        for (std::string t; ss >> t;) tok.push_back(t);
        size_t at = 0;
        const auto value = [&](size_t pi, long long k) {
          char* end = nullptr;
          const double x = std::strtod(tok[at].c_str(), &end);
          if (*end) truncated(e, item, "line " + std::to_string(lineno) + ": '" + tok[at] + "' is not a number");
          visit(ei, item, pi, k, x);
        };
        for (size_t pi = 0; pi < e.properties.size(); ++pi) {
          const Property& prop = e.properties[pi];
          if (at >= tok.size()) truncated(e, item, "line " + std::to_string(lineno) + " has too few values (corrupt or truncated?)");
          if (!prop.list) {
            if (visit) value(pi, -1);
            ++at;
            continue;
          }
          char* end = nullptr;
          const double n = std::strtod(tok[at].c_str(), &end);
          if (*end || !(n >= 0) || n != std::floor(n) || n > static_cast<double>(tok.size() - at - 1))
            truncated(e, item, "line " + std::to_string(lineno) + ": list count '" + tok[at] + "' is not the number of values after it (corrupt or truncated?)");
          ++at;
          for (long long k = 0; k < static_cast<long long>(n); ++k, ++at)
            if (visit) value(pi, k);
        }
      }
    }
    return;
  }
  // Binary: the body in memory (the file was read whole by assimp anyway).
  const std::streamoff header_end = in.tellg();
  std::error_code ec;
  const auto size = fs::file_size(path, ec);
  if (ec) throw InputError(name + ": cannot read its size");
  std::vector<unsigned char> body(static_cast<size_t>(size) - static_cast<size_t>(header_end));
  in.read(reinterpret_cast<char*>(body.data()), static_cast<std::streamsize>(body.size()));
  size_t at = 0;
  const auto count_at = [&](size_t pos, int bytes) -> unsigned long long {
    unsigned long long v = 0;
    for (int b = 0; b < bytes; ++b) {
      const unsigned long long byte = body[pos + static_cast<size_t>(big_endian ? b : bytes - 1 - b)];
      v = (v << 8) | byte;
    }
    return v;
  };
  // A scalar of `type` at pos, in the file's byte order.
  const auto value_at = [&](size_t pos, const std::string& type, int bytes) -> double {
    unsigned char b[8];
    for (int k = 0; k < bytes; ++k) b[k] = body[pos + static_cast<size_t>(big_endian ? bytes - 1 - k : k)];  // little-endian in b
    unsigned long long u = 0;
    for (int k = bytes - 1; k >= 0; --k) u = (u << 8) | b[k];
    if (type == "float" || type == "float32") {
      float f;
      const auto u32 = static_cast<std::uint32_t>(u);
      std::memcpy(&f, &u32, 4);
      return f;
    }
    if (type == "double" || type == "float64") {
      double d;
      std::memcpy(&d, &u, 8);
      return d;
    }
    const bool is_signed = type == "char" || type == "short" || type.compare(0, 3, "int") == 0;  // (int, int8-int32)
    if (is_signed && bytes < 8 && (u >> (8 * bytes - 1)) & 1u) return static_cast<double>(static_cast<long long>(u) - (1LL << (8 * bytes)));
    return static_cast<double>(u);
  };
  for (size_t ei = 0; ei < elements.size(); ++ei) {
    const Element& e = elements[ei];
    for (long long item = 0; item < e.count; ++item)
      for (size_t pi = 0; pi < e.properties.size(); ++pi) {
        const Property& prop = e.properties[pi];
        if (!prop.list) {
          if (body.size() - at < static_cast<size_t>(prop.size)) truncated(e, item, "past the end of the file (truncated?)");
          if (visit) visit(ei, item, pi, -1, value_at(at, prop.type, prop.size));
          at += static_cast<size_t>(prop.size);
          continue;
        }
        if (body.size() - at < static_cast<size_t>(prop.count_size)) truncated(e, item, "past the end of the file (truncated?)");
        unsigned long long n = count_at(at, prop.count_size);
        // A negative count of a signed type reads as a huge one here, and is refused below.
        at += static_cast<size_t>(prop.count_size);
        if (n > (body.size() - at) / static_cast<size_t>(prop.size))
          truncated(e, item, "list of " + std::to_string(n) + " values past the end of the file (corrupt or truncated?)");
        if (visit)
          for (unsigned long long k = 0; k < n; ++k)
            visit(ei, item, pi, static_cast<long long>(k), value_at(at + k * static_cast<size_t>(prop.size), prop.type, prop.size));
        at += static_cast<size_t>(n) * static_cast<size_t>(prop.size);
      }
  }
}

// A PLY file whose triangles come as strips (an element `tristrips` with a list `vertex_indices`, -1
// restarting a strip: the Stanford and VCG exporters' igea, for one), which Debian's assimp 5.2 reads
// as one triangle. Read here, from check_ply's walk of the body (take()): the `vertex` element's x,
// y, z; each strip's triangle k made of its items k, k+1, k+2, every other one turned to keep the
// strip's orientation (the first as written), those with a repeated vertex (joins between strips)
// dropped; a `face` element too, if any, each polygon as a fan. Throws InputError naming the strip
// or face with an index that is not a whole number, or out of range.
class PlyStrips {
 public:
  PlyStrips(std::string name, const PlyLayout& layout) : name_(std::move(name)) {
    const auto element = [&](const std::string& e) -> long {
      for (size_t i = 0; i < layout.size(); ++i)
        if (layout[i].first == e) return static_cast<long>(i);
      return -1;
    };
    const auto property = [&](long e, std::initializer_list<const char*> names) -> long {
      if (e < 0) return -1;
      const auto& props = layout[static_cast<size_t>(e)].second;
      for (const char* n : names)
        for (size_t i = 0; i < props.size(); ++i)
          if (props[i] == n) return static_cast<long>(i);
      return -1;
    };
    ev_ = element("vertex"), es_ = element("tristrips"), ef_ = element("face");
    px_ = property(ev_, {"x"}), py_ = property(ev_, {"y"}), pz_ = property(ev_, {"z"});
    ps_ = property(es_, {"vertex_indices", "vertex_index"}), pf_ = property(ef_, {"vertex_indices", "vertex_index"});
    if (px_ < 0 || py_ < 0 || pz_ < 0) throw InputError(name_ + ": PLY has no vertex element with x, y and z");
    if (ps_ < 0) throw InputError(name_ + ": PLY tristrips element has no list vertex_indices");
  }

  // One value of the body (check_ply's visitor).
  void take(size_t e, long long item, size_t prop, long long at, double x) {
    const long ei = static_cast<long>(e), pi = static_cast<long>(prop);
    const bool strip = ei == es_ && pi == ps_ && at >= 0, face = ei == ef_ && pi == pf_ && at >= 0;
    if ((strip || face) && !(std::abs(x) < 4e18 && x == std::floor(x)))
      throw InputError(name_ + ": PLY " + (strip ? "tristrips " : "face ") + std::to_string(item) + ": '" +
                       std::to_string(x) + "' is not a vertex index");
    if (ei == ev_ && at < 0) {
      if (static_cast<size_t>(item) >= pts_.size()) pts_.resize(static_cast<size_t>(item) + 1);
      const int k = pi == px_ ? 0 : pi == py_ ? 1 : pi == pz_ ? 2 : -1;
      if (k >= 0) pts_[static_cast<size_t>(item)][static_cast<size_t>(k)] = x;
    } else if (strip) {
      if (at == 0 && !strip_.empty()) strip_.emplace_back(-1, item);  // (a new strip item restarts)
      strip_.emplace_back(static_cast<long long>(x), item);
    } else if (face) {
      if (at == 0) faces_.emplace_back();
      faces_.back().push_back(static_cast<long long>(x));
    }
  }

  // The points and triangles, once the body is read.
  void triangles(std::vector<std::array<double, 3>>& pts, std::vector<std::array<int, 3>>& tris) {
    const auto n = static_cast<long long>(pts_.size());
    const auto in_range = [&](long long v, const std::string& where) {
      if (v < 0 || v >= n)
        throw InputError(name_ + ": PLY " + where + ": vertex index " + std::to_string(v) + " out of range (" +
                         std::to_string(n) + " vertices)");
      return static_cast<int>(v);
    };
    std::array<long long, 2> last{-1, -1};
    int k = 0;  // triangles of the current strip so far
    for (const auto& [v, item] : strip_) {
      if (v == -1) {
        last = {-1, -1};
        k = 0;
        continue;
      }
      const int c = in_range(v, "tristrips " + std::to_string(item));
      if (last[0] >= 0 && last[1] >= 0) {
        const int a = static_cast<int>(last[0]), b = static_cast<int>(last[1]);
        if (a != b && b != c && c != a) tris.push_back(k % 2 == 0 ? std::array<int, 3>{a, b, c} : std::array<int, 3>{b, a, c});
        ++k;
      }
      last = {last[1], c};
    }
    for (size_t f = 0; f < faces_.size(); ++f) {
      const auto& poly = faces_[f];
      const std::string where = "face " + std::to_string(f);
      for (size_t i = 1; i + 1 < poly.size(); ++i)
        tris.push_back({in_range(poly[0], where), in_range(poly[i], where), in_range(poly[i + 1], where)});
    }
    pts = std::move(pts_);
  }

 private:
  std::string name_;
  long ev_, es_, ef_, px_, py_, pz_, ps_, pf_;  // elements' and properties' indices (-1: none)
  std::vector<std::array<double, 3>> pts_;
  std::vector<std::pair<long long, long long>> strip_;  // (index, strip item) in file order; -1 restarts
  std::vector<std::vector<long long>> faces_;
};

// OFF in file order and full double precision (assimp parses OFF in single precision): header
// OFF, COFF, NOFF or CNOFF (extra per-vertex columns ignored), '#' comments, polygons as fans.
void read_off_in_order(const fs::path& path, std::vector<std::array<double, 3>>& pts,
                       std::vector<std::array<int, 3>>& tris) {
  const std::string name = path.string();
  std::ifstream in(path);
  if (!in) throw InputError(name + ": cannot open for reading");
  std::string line;
  long lineno = 0;
  auto next = [&](std::istringstream& ss) {  // next non-empty, non-comment line
    while (std::getline(in, line)) {
      ++lineno;
      const auto hash = line.find('#');
      if (hash != std::string::npos) line.resize(hash);
      if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
      ss.clear();
      ss.str(line);
      return true;
    }
    return false;
  };
  auto fail = [&](const std::string& what) {
    throw InputError(name + ": line " + std::to_string(lineno) + ": " + what);
  };
  std::istringstream ss;
  std::string header;
  if (!next(ss) || !(ss >> header) ||
      !(header == "OFF" || header == "COFF" || header == "NOFF" || header == "CNOFF"))
    fail("not an ASCII OFF file (header " + header + ")");
  long nv = -1, nf = -1;
  if (!(ss >> nv)) {
    if (!next(ss) || !(ss >> nv)) fail("missing vertex and face counts");
  }
  if (!(ss >> nf) || nv < 0 || nf < 0) fail("malformed vertex and face counts");
  if (nv == 0) throw InputError(name + ": holds no vertices");
  {  // the counts against the file's size before allocating: a vertex line takes at least 6 bytes
     // ("0 0 0\n"), a face line 2
    std::error_code ec;
    const double size = static_cast<double>(fs::file_size(path, ec));
    if (!ec && 6.0 * nv + 2.0 * nf > size)
      fail("counts of " + std::to_string(nv) + " vertices and " + std::to_string(nf) + " faces do not fit in a file of " +
           std::to_string(static_cast<long long>(size)) + " bytes (truncated or corrupt?)");
  }
  pts.resize(static_cast<size_t>(nv));
  for (auto& p : pts) {
    if (!next(ss)) fail("ends before its " + std::to_string(nv) + " vertices");
    std::string tok;
    for (double& d : p) {  // strtod, unlike >>, reads nan and inf (rejected by the caller)
      if (!(ss >> tok)) fail("malformed vertex");
      char* end = nullptr;
      d = std::strtod(tok.c_str(), &end);
      if (*end) fail("malformed vertex coordinate '" + tok + "'");
    }
  }
  std::vector<long> poly;
  for (long f = 0; f < nf; ++f) {
    if (!next(ss)) fail("ends before its " + std::to_string(nf) + " faces");
    long n = 0;
    if (!(ss >> n) || n < 0) fail("malformed face");
    if (static_cast<double>(n) > static_cast<double>(line.size()) / 2 + 1)  // each index takes 2 characters at least
      fail("a face of " + std::to_string(n) + " corners on a line of " + std::to_string(line.size()) + " characters");
    poly.resize(static_cast<size_t>(n));
    for (long& v : poly)
      if (!(ss >> v)) fail("malformed face");
      else if (v < 0 || v >= nv) fail("vertex index " + std::to_string(v) + " out of range");
    triangulate_polygon(pts, poly, tris);
  }
}

// Our own OFF writer: assimp 5.2 has no OFF exporter, and OFF is the format of our test corpus.
void write_off(const fs::path& path, const SurfaceMesh& mesh) {
  std::ofstream out(path);
  if (!out) throw InputError(path.string() + ": cannot open for writing");
  out.precision(17);
  out << "OFF\n" << mesh.V.rows() << ' ' << mesh.F.rows() << " 0\n";
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
    out << mesh.V(i, 0) << ' ' << mesh.V(i, 1) << ' ' << mesh.V(i, 2) << '\n';
  for (Eigen::Index i = 0; i < mesh.F.rows(); ++i)
    out << "3 " << mesh.F(i, 0) << ' ' << mesh.F(i, 1) << ' ' << mesh.F(i, 2) << '\n';
  if (!out) throw InputError(path.string() + ": write failed");
}

// Our own OBJ writer: full precision, and every vertex in order (assimp's exporter re-indexes).
void write_obj(const fs::path& path, const SurfaceMesh& mesh) {
  std::ofstream out(path);
  if (!out) throw InputError(path.string() + ": cannot open for writing");
  out.precision(17);
  for (Eigen::Index i = 0; i < mesh.V.rows(); ++i)
    out << "v " << mesh.V(i, 0) << ' ' << mesh.V(i, 1) << ' ' << mesh.V(i, 2) << '\n';
  for (Eigen::Index i = 0; i < mesh.F.rows(); ++i)
    out << "f " << mesh.F(i, 0) + 1 << ' ' << mesh.F(i, 1) + 1 << ' ' << mesh.F(i, 2) + 1 << '\n';
  if (!out) throw InputError(path.string() + ": write failed");
}

// The surface formats squeeze reads or writes with its own code; every other extension is
// assimp's (any format it imports; any it exports, see assimp_format_id). To add a format: its
// reader and/or writer in this file and one line here.
struct OwnSurfaceFormat {
  const char* extension;  // lower case, with the dot
  // Reader in file order and double precision (vertices as written, polygons as fans), or null.
  void (*read)(const fs::path& path, std::vector<std::array<double, 3>>& pts, std::vector<std::array<int, 3>>& tris);
  bool read_always;  // the reader serves every load; false: only LoadOptions::keep_order (assimp otherwise)
  // Writer: full precision, every vertex of V in order; null: assimp exports the format.
  void (*write)(const fs::path& path, const SurfaceMesh& mesh);
};

constexpr OwnSurfaceFormat kOwnSurfaceFormats[] = {
    // OFF: ours in all modes (assimp reads it in single precision, and reports no NaN).
    {".off", read_off_in_order, true, write_off},
    // OBJ: ours in all modes too. Only geometry matters here (materials and groups are merged
    // anyway); assimp duplicates vertices per face corner, reads single precision, and turns a
    // face whose texture index has no `vt` line into a one-vertex point (assimp 5.2).
    {".obj", read_obj_in_order, true, write_obj},
};

const OwnSurfaceFormat* own_surface_format(const std::string& ext) {
  for (const OwnSurfaceFormat& f : kOwnSurfaceFormats)
    if (ext == f.extension) return &f;
  return nullptr;
}

// A vertex far outside the rest of the model (a stray vertex at 1e11 m, a units mix-up) makes the
// bounding box, and every tolerance relative to it, meaningless: the mesh comes out empty or the
// meshing takes minutes. The rest of the model is the box between the 1st and 99th percentile of
// each coordinate; a vertex more than 1000 times its diagonal away from it is an error.
void check_outliers(const std::string& name, const std::vector<std::array<double, 3>>& pts) {
  if (pts.size() < 20) return;
  std::array<double, 3> lo{}, hi{};
  std::vector<double> c(pts.size());
  for (int k = 0; k < 3; ++k) {
    for (size_t i = 0; i < pts.size(); ++i) c[i] = pts[i][k];
    const size_t a = pts.size() / 100, b = pts.size() - 1 - pts.size() / 100;
    std::nth_element(c.begin(), c.begin() + static_cast<long>(a), c.end());
    lo[k] = c[a];
    std::nth_element(c.begin(), c.begin() + static_cast<long>(b), c.end());
    hi[k] = c[b];
  }
  const double diag = std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                (hi[2] - lo[2]) * (hi[2] - lo[2]));
  if (!(diag > 0)) return;  // degenerate bulk: other checks report it
  for (size_t i = 0; i < pts.size(); ++i) {
    double d2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double out = std::max({0.0, lo[k] - pts[i][k], pts[i][k] - hi[k]});
      d2 += out * out;
    }
    if (std::sqrt(d2) > 1000 * diag) {
      std::ostringstream s;
      s << name << ": vertex " << i << " at (" << pts[i][0] << ", " << pts[i][1] << ", " << pts[i][2] << ") lies "
        << std::sqrt(d2) / diag << " times the size of the rest of the model away from it (a stray vertex or mixed "
        << "units: remove it or fix the file)";
      throw InputError(s.str());
    }
  }
}

// Reads `name` with `importer` (ReadFile with `flags`, then collect) into pts and tris; throws
// InputError where assimp cannot read it or collect finds it broken. The scene lives as long as
// the importer.
void read_with_assimp(const std::string& name, unsigned flags, Assimp::Importer& importer,
                      std::vector<std::array<double, 3>>& pts, std::vector<std::array<int, 3>>& tris) {
  const aiScene* scene = importer.ReadFile(name, flags);
  if (!scene || !scene->mRootNode) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown or unreadable format";
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw InputError(name + ": cannot read: " + why);
  }
  collect(name, scene, scene->mRootNode, aiMatrix4x4(), pts, tris);
}

// All of `size` bytes written to fd (a pipe); false on an error.
bool write_all(int fd, const void* data, size_t size) {
  const char* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t n = ::write(fd, p, size);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    p += n;
    size -= static_cast<size_t>(n);
  }
  return true;
}

// read_with_assimp in a child process (fork), which sends back the triangles or the error and
// ends without destroying assimp's scene (its stderr closed). Debian's assimp 5.2 crashes on files
// it has read:
// destroying the scene of some 3MF files frees memory twice ("double free or corruption", assimp
// issue #5328; trimesh's counterX.3MF, counterXP.3MF and cube_and_sphere_same_name.3mf), and its
// importers have aborted on corrupt files (see load_surface). Whatever assimp does there, the
// caller gets the triangles or one InputError naming the file. Message from the child: a status
// byte ('t': triangles, 'e': an error), then for 't' the point count, the points, the triangle
// count and the triangles, for 'e' the message's length and the message.
void read_with_assimp_in_child(const std::string& name, unsigned flags, std::vector<std::array<double, 3>>& pts,
                               std::vector<std::array<int, 3>>& tris) {
  // Where no child can be started (out of processes or memory, a sandbox without fork), the file
  // is read in this process, as LoadOptions::assimp_in_child = false does, with a warning.
  auto in_process = [&](const char* what, int err) {
    spdlog::warn("{}: reading it in this process ({}: {})", name, what, std::strerror(err));
    Assimp::Importer importer;
    read_with_assimp(name, flags, importer, pts, tris);
  };
  int fds[2];  // (close-on-exec: a program another thread starts meanwhile must not hold the write end open)
  if (::pipe2(fds, O_CLOEXEC) != 0) return in_process("no pipe for the importer's child process", errno);
  const pid_t pid = ::fork();
  if (pid < 0) {
    const int err = errno;
    ::close(fds[0]);
    ::close(fds[1]);
    return in_process("cannot start the importer's child process", err);
  }
  if (pid == 0) {  // the child: no return, no destructors (the importer is never deleted), no exit handlers
    ::close(fds[0]);
    if (const int null = ::open("/dev/null", O_WRONLY); null >= 0) ::dup2(null, 2);  // (glibc's "double free")
    bool ok = true;
    try {
      std::vector<std::array<double, 3>> p;
      std::vector<std::array<int, 3>> t;
      read_with_assimp(name, flags, *new Assimp::Importer, p, t);
      const uint64_t np = p.size(), nt = t.size();
      ok = write_all(fds[1], "t", 1) && write_all(fds[1], &np, sizeof np) &&
           write_all(fds[1], p.data(), p.size() * sizeof p[0]) && write_all(fds[1], &nt, sizeof nt) &&
           write_all(fds[1], t.data(), t.size() * sizeof t[0]);
    } catch (const std::exception& e) {
      const std::string what = e.what();
      const uint64_t n = what.size();
      ok = write_all(fds[1], "e", 1) && write_all(fds[1], &n, sizeof n) && write_all(fds[1], what.data(), what.size());
    } catch (...) {
      ok = false;
    }
    ::_exit(ok ? 0 : 1);
  }
  ::close(fds[1]);
  std::string msg;
  {
    char buf[1 << 16];
    for (;;) {
      const ssize_t n = ::read(fds[0], buf, sizeof buf);
      if (n < 0 && errno == EINTR) continue;
      if (n <= 0) break;
      msg.append(buf, static_cast<size_t>(n));
    }
  }
  ::close(fds[0]);
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  size_t at = 1;
  auto take = [&](void* out, size_t size) {
    if (msg.size() - at < size) return false;
    std::memcpy(out, msg.data() + at, size);
    at += size;
    return true;
  };
  uint64_t n = 0;
  if (!msg.empty() && msg[0] == 'e' && take(&n, sizeof n) && n == msg.size() - at)
    throw InputError(msg.substr(at));
  if (!msg.empty() && msg[0] == 't' && take(&n, sizeof n) && n <= (msg.size() - at) / sizeof pts[0]) {
    pts.resize(n);
    uint64_t m = 0;
    if (take(pts.data(), n * sizeof pts[0]) && take(&m, sizeof m) && m == (msg.size() - at) / sizeof tris[0] &&
        (msg.size() - at) % sizeof tris[0] == 0) {
      tris.resize(m);
      take(tris.data(), m * sizeof tris[0]);
      if (WIFEXITED(status) && WEXITSTATUS(status) == 0) return;
    }
  }
  const std::string how = WIFSIGNALED(status) ? std::string("crashed: ") + strsignal(WTERMSIG(status))
                                              : "ended with status " + std::to_string(WEXITSTATUS(status));
  throw InputError(name + ": cannot read: assimp's importer " + how + " (a bug of assimp's reader for this format; "
                   "convert the file to OFF, OBJ, PLY or STL)");
}

}  // namespace

SurfaceMesh load_surface(const fs::path& path, const LoadOptions& options) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(name + ": no such file");
  if (fs::is_directory(path, ec)) throw InputError(name + ": is a directory, not a mesh file");
  if (!fs::is_regular_file(path, ec)) throw InputError(name + ": is not a regular file (a device, a pipe or a socket)");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputError(name + ": cannot open for reading");
    if (probe.peek() == std::ifstream::traits_type::eof()) throw InputError(name + ": file is empty");
  }
  std::vector<std::array<double, 3>> pts;
  std::vector<std::array<int, 3>> tris;
  const OwnSurfaceFormat* own = own_surface_format(lower(path.extension().string()));
  if (own && own->read && (own->read_always || options.keep_order)) {
    own->read(path, pts, tris);
  } else {
    // (A PLY of triangle strips is read by PlyStrips, in the same walk of its body as the check.)
    std::optional<PlyStrips> strips;
    if (lower(path.extension().string()) == ".ply")
      check_ply(path, [&](const PlyLayout& layout) -> PlyVisitor {
        if (std::none_of(layout.begin(), layout.end(), [](const auto& e) { return e.first == "tristrips"; })) return nullptr;
        strips.emplace(name, layout);
        return [&](size_t e, long long item, size_t prop, long long at, double x) { strips->take(e, item, prop, at, x); };
      });
    // Only aiProcess_ValidateDataStructure: indices past the vertex list (a truncated or corrupt
    // file) are reported as an error. No assimp triangulation: collect() splits polygons as fans and
    // drops points and lines itself, because Debian's assimp 5.2 aborts the process (ai_assert) in
    // aiProcess_Triangulate on a corrupt ASCII PLY face that passes validation (found by
    // fuzz_surface; tests/fuzz/fuzz_surface/ keeps the input). Welding is ours too (below).
    const unsigned flags = aiProcess_ValidateDataStructure |
                           (options.keep_order || options.merge_coincident ? 0u : aiProcess_JoinIdenticalVertices);
    if (strips) {
      strips->triangles(pts, tris);
    } else if (options.assimp_in_child) {
      read_with_assimp_in_child(name, flags, pts, tris);
    } else {
      Assimp::Importer importer;
      read_with_assimp(name, flags, importer, pts, tris);
    }
  }
  if (pts.empty()) throw InputError(name + ": holds no vertices");
  if (tris.empty()) throw InputError(name + ": holds no triangles");
  for (size_t i = 0; i < pts.size(); ++i)
    for (double d : pts[i])
      if (!std::isfinite(d))
        throw InputError(name + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
  check_outliers(name, pts);

  if (options.keep_order) {  // the file's vertices and faces as they are
    SurfaceMesh mesh;
    mesh.V.resize(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t i = 0; i < pts.size(); ++i)
      mesh.V.row(static_cast<Eigen::Index>(i)) << pts[i][0], pts[i][1], pts[i][2];
    mesh.F.resize(static_cast<Eigen::Index>(tris.size()), 3);
    for (size_t i = 0; i < tris.size(); ++i)
      mesh.F.row(static_cast<Eigen::Index>(i)) << tris[i][0], tris[i][1], tris[i][2];
    return mesh;
  }

  // Weld identical coordinates (across meshes too), keep first-occurrence order of used vertices.
  std::vector<int> remap(pts.size(), -1);
  std::vector<std::array<double, 3>> kept;
  if (options.merge_coincident) {
    std::unordered_map<std::array<double, 3>, int, KeyHash> seen;
    seen.reserve(pts.size() * 2);
    for (const auto& t : tris)
      for (int v : t) {
        if (remap[v] >= 0) continue;
        auto [it, inserted] = seen.emplace(pts[v], static_cast<int>(kept.size()));
        if (inserted) kept.push_back(pts[v]);
        remap[v] = it->second;
      }
    // ... and coordinates within weld_tolerance of the bounding-box diagonal of each other, in
    // every coordinate (a point computed two ways, 0.6 × 4/6 and 0.4, a few ulps apart): each to
    // the first of its cluster. A sweep along x over the vertices sorted by x.
    std::array<double, 3> lo = kept.empty() ? std::array<double, 3>{} : kept.front(), hi = lo;
    for (const auto& q : kept)
      for (int k = 0; k < 3; ++k) lo[k] = std::min(lo[k], q[k]), hi[k] = std::max(hi[k], q[k]);
    const double tol = options.weld_tolerance *
                       std::sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (tol > 0) {
      std::vector<int> order(kept.size()), first(kept.size());
      for (size_t i = 0; i < kept.size(); ++i) order[i] = first[i] = static_cast<int>(i);
      std::sort(order.begin(), order.end(), [&](int a, int b) { return kept[a][0] < kept[b][0]; });
      auto root = [&](int i) {
        while (first[i] != i) i = first[i] = first[first[i]];
        return i;
      };
      for (size_t i = 0; i < order.size(); ++i)
        for (size_t j = i + 1; j < order.size() && kept[order[j]][0] - kept[order[i]][0] <= tol; ++j) {
          const auto& a = kept[order[i]];
          const auto& b = kept[order[j]];
          if (std::abs(a[1] - b[1]) <= tol && std::abs(a[2] - b[2]) <= tol) {
            const int ra = root(order[i]), rb = root(order[j]);
            first[std::max(ra, rb)] = std::min(ra, rb);  // the cluster's first vertex is its root
          }
        }
      std::vector<int> renumber(kept.size(), -1);
      std::vector<std::array<double, 3>> welded;
      int merged = 0;
      for (size_t i = 0; i < kept.size(); ++i) {
        const int r = root(static_cast<int>(i));
        if (renumber[r] < 0) {
          renumber[r] = static_cast<int>(welded.size());
          welded.push_back(kept[r]);
        }
        renumber[i] = renumber[r];
        merged += r != static_cast<int>(i);
      }
      if (merged > 0) {
        for (int& v : remap)
          if (v >= 0) v = renumber[v];
        kept = std::move(welded);
      }
    }
  } else {
    for (const auto& t : tris)
      for (int v : t)
        if (remap[v] < 0) {
          remap[v] = static_cast<int>(kept.size());
          kept.push_back(pts[v]);
        }
  }
  std::vector<std::array<int, 3>> faces;
  faces.reserve(tris.size());
  for (const auto& t : tris) {
    std::array<int, 3> f{remap[t[0]], remap[t[1]], remap[t[2]]};
    if (options.drop_degenerate && (f[0] == f[1] || f[1] == f[2] || f[0] == f[2])) continue;
    faces.push_back(f);
  }
  if (faces.empty()) throw InputError(name + ": every face is degenerate");

  SurfaceMesh mesh;
  mesh.V.resize(static_cast<Eigen::Index>(kept.size()), 3);
  for (size_t i = 0; i < kept.size(); ++i)
    mesh.V.row(static_cast<Eigen::Index>(i)) << kept[i][0], kept[i][1], kept[i][2];
  mesh.F.resize(static_cast<Eigen::Index>(faces.size()), 3);
  for (size_t i = 0; i < faces.size(); ++i)
    mesh.F.row(static_cast<Eigen::Index>(i)) << faces[i][0], faces[i][1], faces[i][2];
  return mesh;
}

namespace {

std::string assimp_format_id(const std::string& ext) {
  Assimp::Exporter exporter;
  std::string fallback;
  for (size_t i = 0; i < exporter.GetExportFormatCount(); ++i) {
    const aiExportFormatDesc* d = exporter.GetExportFormatDescription(i);
    if (lower(d->fileExtension) != ext) continue;
    // Prefer binary variants for ply/stl/gltf (smaller, exact float32), as assimp lists them.
    const std::string id = d->id;
    if (id == "plyb" || id == "stlb" || id == "glb2" || id == "gltf2") return id;
    if (fallback.empty()) fallback = id;
  }
  return fallback;
}

}  // namespace

void save_surface(const fs::path& path, const SurfaceMesh& mesh) {
  const std::string ext = lower(path.extension().string().empty() ? "" : path.extension().string().substr(1));
  if (const OwnSurfaceFormat* own = own_surface_format("." + ext); own && own->write) {
    write_atomically(path, [&](const fs::path& tmp) { own->write(tmp, mesh); });
    return;
  }
  const std::string format = assimp_format_id(ext);
  if (format.empty())
    throw InputError(path.string() + ": unknown output format '." + ext + "' (use " + surface_format_examples() + ")");
  aiScene scene;
  scene.mRootNode = new aiNode();
  scene.mMaterials = new aiMaterial*[1]{new aiMaterial()};
  scene.mNumMaterials = 1;
  scene.mMeshes = new aiMesh*[1]{new aiMesh()};
  scene.mNumMeshes = 1;
  scene.mRootNode->mMeshes = new unsigned[1]{0};
  scene.mRootNode->mNumMeshes = 1;
  aiMesh* m = scene.mMeshes[0];
  m->mMaterialIndex = 0;
  m->mPrimitiveTypes = aiPrimitiveType_TRIANGLE;
  m->mNumVertices = static_cast<unsigned>(mesh.V.rows());
  m->mVertices = new aiVector3D[m->mNumVertices];
  for (unsigned i = 0; i < m->mNumVertices; ++i)
    m->mVertices[i] = aiVector3D(static_cast<ai_real>(mesh.V(i, 0)), static_cast<ai_real>(mesh.V(i, 1)),
                                 static_cast<ai_real>(mesh.V(i, 2)));
  m->mNumFaces = static_cast<unsigned>(mesh.F.rows());
  m->mFaces = new aiFace[m->mNumFaces];
  for (unsigned f = 0; f < m->mNumFaces; ++f) {
    m->mFaces[f].mNumIndices = 3;
    m->mFaces[f].mIndices = new unsigned[3]{static_cast<unsigned>(mesh.F(f, 0)),
                                            static_cast<unsigned>(mesh.F(f, 1)),
                                            static_cast<unsigned>(mesh.F(f, 2))};
  }
  // Export into a temporary folder beside the target under the final name (so that side files such
  // as a .gltf's .bin are named right), then move side files, and the main file last.
  check_output_directory(path);
  const fs::path dir = path.has_parent_path() ? path.parent_path() : fs::path(".");
  std::error_code ec;
  const fs::path tmpdir = temporary_sibling(fs::path(path).replace_extension(".dir"));
  if (!fs::create_directory(tmpdir, ec) || ec)
    throw InputError(path.string() + ": cannot write in " + dir.string() + ": " + ec.message());
  try {
    Assimp::Exporter exporter;
    if (exporter.Export(&scene, format, (tmpdir / path.filename()).string()) != aiReturn_SUCCESS) {
      std::string why = exporter.GetErrorString();
      std::replace(why.begin(), why.end(), '\n', ' ');
      throw InputError(path.string() + ": cannot write: " + why);
    }
    std::vector<fs::path> side;
    for (const auto& entry : fs::directory_iterator(tmpdir))
      if (entry.path().filename() != path.filename()) side.push_back(entry.path());
    std::sort(side.begin(), side.end());
    for (const auto& f : side) fs::rename(f, dir / f.filename());
    fs::rename(tmpdir / path.filename(), path);
  } catch (const fs::filesystem_error& e) {
    fs::remove_all(tmpdir, ec);
    throw InputError(path.string() + ": cannot write: " + e.code().message());
  } catch (...) {
    fs::remove_all(tmpdir, ec);
    throw;
  }
  fs::remove_all(tmpdir, ec);
}

bool is_surface_format(const fs::path& path) {
  const std::string ext = lower(path.extension().string().empty() ? "" : path.extension().string().substr(1));
  const OwnSurfaceFormat* own = own_surface_format("." + ext);
  return (own && own->write) || !assimp_format_id(ext).empty();
}

std::string surface_format_examples() {
  std::string list;
  for (const OwnSurfaceFormat& f : kOwnSurfaceFormats)
    if (f.write) list += std::string(f.extension) + ", ";
  return list + ".ply, .stl, .gltf, .glb, ...";  // a few of assimp's
}

}  // namespace squeeze::meshing
