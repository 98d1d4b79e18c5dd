#include "squeeze/meshing/tet_io.h"

#include <algorithm>
#include <array>
#include <unordered_map>
#include <cmath>
#include <fstream>
#include <limits>
#include <sstream>
#include <string>
#include <vector>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

namespace squeeze::meshing {
namespace fs = std::filesystem;

namespace {

std::string ext_of(const fs::path& p) {
  std::string e = p.extension().string();
  std::transform(e.begin(), e.end(), e.begin(), [](unsigned char c) { return std::tolower(c); });
  return e;
}

int label_of(const TetMesh& m, Eigen::Index t) { return m.label.size() ? m.label(t) : 1; }

std::ofstream open_out(const fs::path& tmp, const fs::path& target) {
  std::ofstream out(tmp);
  if (!out) throw InputError(target.string() + ": cannot open for writing");
  out.precision(17);
  return out;
}

void finish(std::ofstream& out, const fs::path& target) {
  out.flush();
  if (!out) throw InputError(target.string() + ": write failed (disk full?)");
}

void write_medit(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << "MeshVersionFormatted 2\nDimension 3\nVertices\n" << m.V.rows() << '\n';
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    out << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << " 0\n";
  out << "Tetrahedra\n" << m.T.rows() << '\n';
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    out << m.T(t, 0) + 1 << ' ' << m.T(t, 1) + 1 << ' ' << m.T(t, 2) + 1 << ' ' << m.T(t, 3) + 1
        << ' ' << label_of(m, t) << '\n';
  out << "End\n";
  finish(out, target);
}

void write_gmsh(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$Nodes\n" << m.V.rows() << '\n';
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    out << i + 1 << ' ' << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
  out << "$EndNodes\n$Elements\n" << m.T.rows() << '\n';
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    out << t + 1 << " 4 2 " << label_of(m, t) << ' ' << label_of(m, t) << ' ' << m.T(t, 0) + 1
        << ' ' << m.T(t, 1) + 1 << ' ' << m.T(t, 2) + 1 << ' ' << m.T(t, 3) + 1 << '\n';
  out << "$EndElements\n";
  finish(out, target);
}

void write_vtk(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << "# vtk DataFile Version 3.0\nsqueeze tetrahedral mesh\nASCII\nDATASET UNSTRUCTURED_GRID\n";
  out << "POINTS " << m.V.rows() << " double\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    out << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
  out << "CELLS " << m.T.rows() << ' ' << 5 * m.T.rows() << '\n';
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    out << "4 " << m.T(t, 0) << ' ' << m.T(t, 1) << ' ' << m.T(t, 2) << ' ' << m.T(t, 3) << '\n';
  out << "CELL_TYPES " << m.T.rows() << '\n';
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) out << "10\n";
  out << "CELL_DATA " << m.T.rows() << "\nSCALARS label int 1\nLOOKUP_TABLE default\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) out << label_of(m, t) << '\n';
  finish(out, target);
}

void write_vtu(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << "<?xml version=\"1.0\"?>\n<VTKFile type=\"UnstructuredGrid\" version=\"0.1\" "
         "byte_order=\"LittleEndian\">\n<UnstructuredGrid>\n<Piece NumberOfPoints=\""
      << m.V.rows() << "\" NumberOfCells=\"" << m.T.rows() << "\">\n";
  out << "<Points>\n<DataArray type=\"Float64\" NumberOfComponents=\"3\" format=\"ascii\">\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    out << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
  out << "</DataArray>\n</Points>\n<Cells>\n"
         "<DataArray type=\"Int64\" Name=\"connectivity\" format=\"ascii\">\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    out << m.T(t, 0) << ' ' << m.T(t, 1) << ' ' << m.T(t, 2) << ' ' << m.T(t, 3) << '\n';
  out << "</DataArray>\n<DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) out << 4 * (t + 1) << '\n';
  out << "</DataArray>\n<DataArray type=\"UInt8\" Name=\"types\" format=\"ascii\">\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) out << "10\n";
  out << "</DataArray>\n</Cells>\n<CellData Scalars=\"label\">\n"
         "<DataArray type=\"Int32\" Name=\"label\" format=\"ascii\">\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t) out << label_of(m, t) << '\n';
  out << "</DataArray>\n</CellData>\n</Piece>\n</UnstructuredGrid>\n</VTKFile>\n";
  finish(out, target);
}

void write_tetgen_node(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << m.V.rows() << " 3 0 0\n";
  for (Eigen::Index i = 0; i < m.V.rows(); ++i)
    out << i << ' ' << m.V(i, 0) << ' ' << m.V(i, 1) << ' ' << m.V(i, 2) << '\n';
  finish(out, target);
}

void write_tetgen_ele(const fs::path& tmp, const fs::path& target, const TetMesh& m) {
  auto out = open_out(tmp, target);
  out << m.T.rows() << " 4 1\n";
  for (Eigen::Index t = 0; t < m.T.rows(); ++t)
    out << t << ' ' << m.T(t, 0) << ' ' << m.T(t, 1) << ' ' << m.T(t, 2) << ' ' << m.T(t, 3) << ' '
        << label_of(m, t) << '\n';
  finish(out, target);
}

// ---- reading ----------------------------------------------------------------------------------

struct Reader {
  fs::path path;
  std::vector<std::array<double, 3>> pts;
  std::vector<std::array<long, 4>> tets;  // as read (64-bit: checked against the vertex count by finish)
  std::vector<long> labels;               // as read (checked to fit an int by finish)

  [[noreturn]] void fail(const std::string& what) const {
    throw InputError(path.string() + ": " + what);
  }
  // A count read from the file, checked before anything is allocated for it: not negative, below
  // 2^31, and `n` items of at least `min_bytes` characters each fit in the file.
  size_t count(long n, double min_bytes, const std::string& what) const {
    if (n < 0) fail("negative " + what + " count " + std::to_string(n));
    if (n > std::numeric_limits<int>::max()) fail(what + " count " + std::to_string(n) + " is above 2^31 - 1");
    std::error_code ec;
    const double size = static_cast<double>(fs::file_size(path, ec));
    if (!ec && static_cast<double>(n) * min_bytes > size)
      fail(what + " count " + std::to_string(n) + " does not fit in a file of " +
           std::to_string(static_cast<long long>(size)) + " bytes (truncated or corrupt?)");
    return static_cast<size_t>(n);
  }
  TetMesh finish(int base) const {
    if (pts.empty()) fail("holds no vertices");
    if (tets.empty()) fail("holds no tetrahedra");
    TetMesh m;
    m.V.resize(static_cast<Eigen::Index>(pts.size()), 3);
    for (size_t i = 0; i < pts.size(); ++i) {
      for (int k = 0; k < 3; ++k) {
        if (!std::isfinite(pts[i][k]))
          fail("vertex " + std::to_string(i) + " has a NaN or infinite coordinate");
        m.V(static_cast<Eigen::Index>(i), k) = pts[i][k];
      }
    }
    m.T.resize(static_cast<Eigen::Index>(tets.size()), 4);
    m.label.resize(static_cast<Eigen::Index>(tets.size()));
    if (!labels.empty() && labels.size() != tets.size())
      fail(std::to_string(labels.size()) + " labels for " + std::to_string(tets.size()) + " tetrahedra");
    for (size_t t = 0; t < tets.size(); ++t) {
      for (int k = 0; k < 4; ++k) {
        const long v = tets[t][k] - static_cast<long>(base);  // 64-bit: no overflow for any int read
        if (v < 0 || v >= static_cast<long>(pts.size()))
          fail("tetrahedron " + std::to_string(t) + " has vertex index " + std::to_string(tets[t][k]) +
               " out of range");
        m.T(static_cast<Eigen::Index>(t), k) = static_cast<int>(v);
      }
      const long label = labels.empty() ? 1 : labels[t];
      if (label < std::numeric_limits<int>::min() || label > std::numeric_limits<int>::max())
        fail("tetrahedron " + std::to_string(t) + " has label " + std::to_string(label) + " outside the int range");
      m.label(static_cast<Eigen::Index>(t)) = static_cast<int>(label);
    }
    return m;
  }
};

std::ifstream open_in(const fs::path& p) {
  std::error_code ec;
  if (!fs::exists(p, ec)) throw InputError(p.string() + ": no such file");
  std::ifstream in(p);
  if (!in) throw InputError(p.string() + ": cannot open for reading");
  return in;
}

template <class T>
void read_value(std::istream& in, T& v, const Reader& r, const char* what) {
  std::string tok;
  if (!(in >> tok)) r.fail(std::string("unexpected end of file while reading ") + what);
  std::istringstream s(tok);
  if (!(s >> v)) {
    if constexpr (std::is_floating_point_v<T>) {
      // Accept nan/inf spelled out so that they are reported as such, not as a syntax error.
      std::string l = tok;
      std::transform(l.begin(), l.end(), l.begin(), [](unsigned char c) { return std::tolower(c); });
      if (l.find("nan") != std::string::npos) { v = std::nan(""); return; }
      if (l.find("inf") != std::string::npos) { v = INFINITY; return; }
    }
    r.fail(std::string("expected a number for ") + what + ", found '" + tok + "'");
  }
}

TetMesh read_medit(const fs::path& p) {
  Reader r{p, {}, {}, {}};
  auto in = open_in(p);
  std::string kw;
  while (in >> kw) {
    if (kw == "Vertices") {
      long n;
      read_value(in, n, r, "vertex count");
      r.pts.resize(r.count(n, 8, "vertex"));  // "0 0 0 0\n"
      for (auto& q : r.pts) {
        read_value(in, q[0], r, "a coordinate");
        read_value(in, q[1], r, "a coordinate");
        read_value(in, q[2], r, "a coordinate");
        int ref;
        read_value(in, ref, r, "a vertex reference");
      }
    } else if (kw == "Tetrahedra") {
      long n;
      read_value(in, n, r, "tetrahedron count");
      r.tets.resize(r.count(n, 10, "tetrahedron"));  // "1 2 3 4 0\n"
      r.labels.resize(r.tets.size());
      for (size_t t = 0; t < r.tets.size(); ++t) {
        for (int k = 0; k < 4; ++k) read_value(in, r.tets[t][k], r, "a tetrahedron index");
        read_value(in, r.labels[t], r, "a tetrahedron reference");
      }
    } else if (kw == "Triangles" || kw == "Edges" || kw == "Corners" || kw == "Quadrilaterals" ||
               kw == "Hexahedra" || kw == "RequiredVertices" || kw == "Ridges") {
      const int per = kw == "Triangles" ? 4 : kw == "Edges" ? 3 : kw == "Quadrilaterals" ? 5
                      : kw == "Hexahedra" ? 9 : 1;
      long n;
      read_value(in, n, r, "an element count");
      r.count(n, 2.0 * per, kw);
      for (long i = 0; i < n * per; ++i) {
        long skip;
        read_value(in, skip, r, "an element index");
      }
    } else if (kw == "End") {
      break;
    }
  }
  return r.finish(1);
}

TetMesh read_gmsh(const fs::path& p) {
  Reader r{p, {}, {}, {}};
  auto in = open_in(p);
  std::string kw;
  std::vector<long> ids;
  std::unordered_map<long, int> id_to_index;
  while (in >> kw) {
    if (kw == "$MeshFormat") {
      double version;
      int file_type;
      read_value(in, version, r, "the format version");
      read_value(in, file_type, r, "the file type");
      if (version >= 3.0 || version < 2.0)
        r.fail("Gmsh format " + std::to_string(version) + " is not supported (write 2.2 ASCII)");
      if (file_type != 0) r.fail("binary Gmsh files are not supported (write 2.2 ASCII)");
    } else if (kw == "$Nodes") {
      long n;
      read_value(in, n, r, "node count");
      r.pts.resize(r.count(n, 8, "node"));  // "1 0 0 0\n"
      for (long i = 0; i < n; ++i) {
        long id;
        read_value(in, id, r, "a node id");
        id_to_index[id] = static_cast<int>(i);
        for (int k = 0; k < 3; ++k) read_value(in, r.pts[static_cast<size_t>(i)][k], r, "a coordinate");
      }
    } else if (kw == "$Elements") {
      long n;
      read_value(in, n, r, "element count");
      r.count(n, 6, "element");  // "1 15 0 1\n" at least
      std::string line;
      std::getline(in, line);
      for (long i = 0; i < n; ++i) {
        if (!std::getline(in, line)) r.fail("unexpected end of file in $Elements");
        std::istringstream ls(line);
        long id, type, ntags;
        if (!(ls >> id >> type >> ntags)) r.fail("malformed element line '" + line + "'");
        if (ntags < 0 || static_cast<double>(ntags) > static_cast<double>(line.size()) / 2)
          r.fail("element " + std::to_string(id) + " has a tag count of " + std::to_string(ntags) + " on a line of " +
                 std::to_string(line.size()) + " characters");
        std::vector<long> tags(static_cast<size_t>(ntags));
        for (auto& t : tags) ls >> t;
        if (type != 4) continue;
        std::array<long, 4> tet;
        for (int k = 0; k < 4; ++k) {
          long node;
          if (!(ls >> node)) r.fail("malformed tetrahedron line '" + line + "'");
          auto it = id_to_index.find(node);
          if (it == id_to_index.end()) r.fail("element " + std::to_string(id) + " names unknown node " + std::to_string(node));
          tet[k] = it->second;
        }
        r.tets.push_back(tet);
        r.labels.push_back(tags.empty() ? 1 : tags[0]);
      }
    }
  }
  return r.finish(0);
}

TetMesh read_vtk(const fs::path& p) {
  Reader r{p, {}, {}, {}};
  auto in = open_in(p);
  std::string kw;
  std::vector<std::vector<long>> cells;
  std::vector<int> types;
  std::vector<long> cell_labels;
  while (in >> kw) {
    if (kw == "BINARY") r.fail("binary legacy VTK is not supported (write ASCII)");
    if (kw == "POINTS") {
      long n;
      std::string type;
      read_value(in, n, r, "point count");
      in >> type;
      r.pts.resize(r.count(n, 6, "point"));  // "0 0 0\n"
      for (auto& q : r.pts)
        for (int k = 0; k < 3; ++k) read_value(in, q[k], r, "a coordinate");
    } else if (kw == "CELLS") {
      long n, size;
      read_value(in, n, r, "cell count");
      read_value(in, size, r, "cell list size");
      cells.resize(r.count(n, 2, "cell"));  // "0\n"
      for (auto& c : cells) {
        int k;
        read_value(in, k, r, "a cell size");
        if (k < 0 || k > 64) r.fail("bad cell size " + std::to_string(k));
        c.resize(static_cast<size_t>(k));
        for (auto& v : c) read_value(in, v, r, "a cell index");
      }
    } else if (kw == "CELL_TYPES") {
      long n;
      read_value(in, n, r, "cell type count");
      types.resize(r.count(n, 2, "cell type"));
      for (auto& t : types) read_value(in, t, r, "a cell type");
    } else if (kw == "SCALARS" && !cells.empty() && !types.empty()) {
      std::string name, type, lookup, table;
      in >> name >> type;
      std::string rest;
      std::getline(in, rest);
      in >> lookup >> table;
      if (name == "label") {
        cell_labels.resize(cells.size());
        for (auto& l : cell_labels) read_value(in, l, r, "a label");
      }
    }
  }
  if (types.size() != cells.size()) r.fail("CELL_TYPES does not match CELLS");
  if (!cell_labels.empty() && cell_labels.size() != cells.size())
    r.fail("the label SCALARS (" + std::to_string(cell_labels.size()) + " values) do not match CELLS (" +
           std::to_string(cells.size()) + ")");
  for (size_t c = 0; c < cells.size(); ++c) {
    if (types[c] != 10) continue;
    if (cells[c].size() != 4) r.fail("tetrahedron cell " + std::to_string(c) + " has " + std::to_string(cells[c].size()) + " vertices");
    r.tets.push_back({cells[c][0], cells[c][1], cells[c][2], cells[c][3]});
    r.labels.push_back(cell_labels.empty() ? 1 : cell_labels[c]);
  }
  return r.finish(0);
}

// Reads the ASCII DataArrays of a .vtu (as written by squeeze, ParaView "ascii" mode).
TetMesh read_vtu(const fs::path& p) {
  Reader r{p, {}, {}, {}};
  auto in = open_in(p);
  std::stringstream ss;
  ss << in.rdbuf();
  const std::string xml = ss.str();
  auto array = [&](const std::string& name_attr, bool points) -> std::string {
    size_t pos = points ? xml.find("<Points>") : xml.find("Name=\"" + name_attr + "\"");
    if (pos == std::string::npos) r.fail("no " + (points ? std::string("Points") : name_attr) + " array");
    // The array whose tag holds the name (search back to its start), or the first one in <Points>.
    pos = points ? xml.find("<DataArray", pos) : xml.rfind("<DataArray", pos);
    if (pos == std::string::npos) r.fail("malformed .vtu (no DataArray)");
    const size_t tag_end = xml.find('>', pos);
    const std::string tag = xml.substr(pos, tag_end - pos);
    if (tag.find("format=\"ascii\"") == std::string::npos)
      r.fail("only ASCII .vtu data arrays are supported");
    const size_t end = xml.find("</DataArray>", tag_end);
    if (tag_end == std::string::npos || end == std::string::npos) r.fail("malformed .vtu (unterminated DataArray)");
    return xml.substr(tag_end + 1, end - tag_end - 1);
  };
  {
    std::istringstream s(array("", true));
    std::array<double, 3> q;
    while (true) {
      std::string a, b, c;
      if (!(s >> a >> b >> c)) break;
      std::istringstream t(a + ' ' + b + ' ' + c);
      t >> q[0] >> q[1] >> q[2];
      if (!t) {
        for (auto* x : {&a, &b, &c})
          if (x->find("nan") != std::string::npos || x->find("inf") != std::string::npos)
            r.fail("vertex " + std::to_string(r.pts.size()) + " has a NaN or infinite coordinate");
        r.fail("malformed point coordinates");
      }
      r.pts.push_back(q);
    }
  }
  std::vector<long> conn, offs, labels;
  std::vector<int> types;
  { std::istringstream s(array("connectivity", false)); long v; while (s >> v) conn.push_back(v); }
  { std::istringstream s(array("offsets", false)); long v; while (s >> v) offs.push_back(v); }
  { std::istringstream s(array("types", false)); int v; while (s >> v) types.push_back(v); }
  if (xml.find("Name=\"label\"") != std::string::npos) {
    std::istringstream s(array("label", false)); long v; while (s >> v) labels.push_back(v);
  }
  if (offs.size() != types.size()) r.fail("offsets and types differ in length");
  long start = 0;
  for (size_t c = 0; c < offs.size(); ++c) {
    if (offs[c] > static_cast<long>(conn.size()) || offs[c] < start) r.fail("bad offsets");
    if (types[c] == 10) {
      if (offs[c] - start != 4) r.fail("tetrahedron cell with " + std::to_string(offs[c] - start) + " vertices");
      r.tets.push_back({conn[start], conn[start + 1], conn[start + 2], conn[start + 3]});
      r.labels.push_back(labels.size() == offs.size() ? labels[c] : 1);
    }
    start = offs[c];
  }
  return r.finish(0);
}

TetMesh read_tetgen(const fs::path& p) {
  const fs::path node = fs::path(p).replace_extension(".node");
  const fs::path ele = fs::path(p).replace_extension(".ele");
  Reader r{node, {}, {}, {}};
  int base = 0;
  {
    auto in = open_in(node);
    long n;
    int dim, nattr, nmark;
    read_value(in, n, r, "node count");
    read_value(in, dim, r, "dimension");
    read_value(in, nattr, r, "attribute count");
    read_value(in, nmark, r, "boundary marker count");
    if (dim != 3) r.fail("dimension must be 3");
    if (nattr < 0 || nmark < 0 || nattr > 1000 || nmark > 1) r.fail("attribute or marker count out of range");
    r.pts.resize(r.count(n, 8.0 + 2 * (nattr + nmark), "node"));
    for (size_t i = 0; i < r.pts.size(); ++i) {
      long id;
      read_value(in, id, r, "a node id");
      if (i == 0) {
        if (id != 0 && id != 1) r.fail("the first node's id is " + std::to_string(id) + " (0 or 1 expected)");
        base = static_cast<int>(id);
      }
      for (int k = 0; k < 3; ++k) read_value(in, r.pts[i][k], r, "a coordinate");
      for (int k = 0; k < nattr + nmark; ++k) { double skip; read_value(in, skip, r, "a node attribute"); }
    }
  }
  Reader re{ele, {}, {}, {}};
  auto in = open_in(ele);
  long n;
  int per, nattr;
  read_value(in, n, re, "tetrahedron count");
  read_value(in, per, re, "nodes per tetrahedron");
  read_value(in, nattr, re, "attribute count");
  if (per != 4 && per != 10) re.fail("nodes per tetrahedron must be 4 or 10");
  if (nattr < 0 || nattr > 1000) re.fail("attribute count " + std::to_string(nattr) + " out of range");
  re.count(n, 2.0 * (1 + per + nattr), "tetrahedron");
  for (long t = 0; t < n; ++t) {
    long id;
    read_value(in, id, re, "a tetrahedron id");
    std::array<long, 4> tet;
    for (int k = 0; k < per; ++k) {
      long v;
      read_value(in, v, re, "a tetrahedron index");
      if (k < 4) tet[k] = v;
    }
    double label = 1;
    for (int k = 0; k < nattr; ++k) read_value(in, label, re, "a region attribute");
    if (!(std::abs(label) <= std::numeric_limits<int>::max()) || label != std::floor(label))
      re.fail("tetrahedron " + std::to_string(id) + " has region attribute " + std::to_string(label) +
              " (an integer in the int range expected)");
    r.tets.push_back(tet);
    r.labels.push_back(static_cast<long>(label));
  }
  r.path = ele;
  return r.finish(base);
}

// ---- writing through temporaries ---------------------------------------------------------------

using FileWriter = void (*)(const fs::path& tmp, const fs::path& target, const TetMesh& m);

// A one-file format's writer: W writes the temporary, renamed to `path` at the end.
template <FileWriter W>
void write_one(const fs::path& path, const TetMesh& m) {
  write_atomically(path, [&](const fs::path& tmp) { W(tmp, path, m); });
}

void write_tetgen(const fs::path& path, const TetMesh& m) {
  write_one<write_tetgen_node>(fs::path(path).replace_extension(".node"), m);
  write_one<write_tetgen_ele>(fs::path(path).replace_extension(".ele"), m);
}

[[noreturn]] void unknown_format(const fs::path& path) {
  throw InputError(path.string() + ": unknown tetrahedral mesh format '" + ext_of(path) + "' (use " +
                   tet_format_list() + ")");
}

}  // namespace

const std::vector<TetFormat>& tet_formats() {
  // One line per format: extensions, short name, description, reader, writer.
  static const std::vector<TetFormat> formats{
      {{".mesh"}, "Medit", "Medit (INRIA), ASCII, MeshVersionFormatted 2 (double precision)", read_medit, write_one<write_medit>},
      {{".msh"}, "Gmsh 2.2", "Gmsh 2.2 ASCII (element type 4 = 4-node tetrahedron)", read_gmsh, write_one<write_gmsh>},
      {{".vtk"}, "", "VTK legacy ASCII unstructured grid (cell type 10)", read_vtk, write_one<write_vtk>},
      {{".vtu"}, "", "VTK XML unstructured grid, ASCII", read_vtu, write_one<write_vtu>},
      {{".node", ".ele"}, "TetGen", "TetGen .node/.ele pair, 0-based", read_tetgen, write_tetgen},
  };
  return formats;
}

const TetFormat* find_tet_format(const fs::path& path) {
  const std::string e = ext_of(path);
  for (const TetFormat& f : tet_formats())
    if (std::find(f.extensions.begin(), f.extensions.end(), e) != f.extensions.end()) return &f;
  return nullptr;
}

bool is_tet_format(const fs::path& path) { return find_tet_format(path) != nullptr; }

std::string tet_format_list(bool names) {
  const auto& formats = tet_formats();
  std::string list;
  for (size_t i = 0; i < formats.size(); ++i) {
    if (i > 0) list += i + 1 == formats.size() ? " or " : ", ";
    for (size_t k = 0; k < formats[i].extensions.size(); ++k) list += (k ? "/" : "") + formats[i].extensions[k];
    if (names && !formats[i].name.empty()) list += " (" + formats[i].name + ")";
  }
  return list;
}

void save_tet_mesh(const fs::path& path, const TetMesh& mesh) {
  const TetFormat* f = find_tet_format(path);
  if (!f) unknown_format(path);
  f->write(path, mesh);
}

TetMesh load_tet_mesh(const fs::path& path) {
  const TetFormat* f = find_tet_format(path);
  if (!f) unknown_format(path);
  return f->read(path);
}

}  // namespace squeeze::meshing
