#include "squeeze/meshing/surface_io.h"

#include <assimp/Exporter.hpp>
#include <assimp/Importer.hpp>
#include <assimp/postprocess.h>
#include <assimp/scene.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <memory>
#include <string>
#include <unordered_map>
#include <vector>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

namespace squeeze {
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
void collect(const aiScene* scene, const aiNode* node, const aiMatrix4x4& parent,
             std::vector<std::array<double, 3>>& pts, std::vector<std::array<int, 3>>& tris) {
  const aiMatrix4x4 m = parent * node->mTransformation;
  for (unsigned k = 0; k < node->mNumMeshes; ++k) {
    const aiMesh* mesh = scene->mMeshes[node->mMeshes[k]];
    const int base = static_cast<int>(pts.size());
    for (unsigned i = 0; i < mesh->mNumVertices; ++i) {
      const aiVector3D p = m * mesh->mVertices[i];
      pts.push_back({p.x, p.y, p.z});
    }
    for (unsigned f = 0; f < mesh->mNumFaces; ++f) {
      const aiFace& face = mesh->mFaces[f];
      for (unsigned j = 2; j < face.mNumIndices; ++j)  // fan; assimp triangulated already
        tris.push_back({base + static_cast<int>(face.mIndices[0]),
                        base + static_cast<int>(face.mIndices[j - 1]),
                        base + static_cast<int>(face.mIndices[j])});
    }
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) collect(scene, node->mChildren[c], m, pts, tris);
}

}  // namespace

SurfaceMesh load_surface(const fs::path& path, const LoadOptions& options) {
  const std::string name = path.string();
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InputError(name + ": no such file");
  if (fs::is_directory(path, ec)) throw InputError(name + ": is a directory, not a mesh file");
  {
    std::ifstream probe(path, std::ios::binary);
    if (!probe) throw InputError(name + ": cannot open for reading");
    if (probe.peek() == std::ifstream::traits_type::eof()) throw InputError(name + ": file is empty");
  }
  Assimp::Importer importer;
  // Keep only triangles; polygons are triangulated, points and lines dropped.
  importer.SetPropertyInteger(AI_CONFIG_PP_SBP_REMOVE, aiPrimitiveType_POINT | aiPrimitiveType_LINE);
  const aiScene* scene = importer.ReadFile(
      name, aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_JoinIdenticalVertices);
  if (!scene || !scene->mRootNode) {
    std::string why = importer.GetErrorString();
    if (why.empty()) why = "unknown or unreadable format";
    std::replace(why.begin(), why.end(), '\n', ' ');
    throw InputError(name + ": cannot read: " + why);
  }
  std::vector<std::array<double, 3>> pts;
  std::vector<std::array<int, 3>> tris;
  collect(scene, scene->mRootNode, aiMatrix4x4(), pts, tris);
  if (tris.empty()) throw InputError(name + ": holds no triangles");
  for (size_t i = 0; i < pts.size(); ++i)
    for (double d : pts[i])
      if (!std::isfinite(d))
        throw InputError(name + ": vertex " + std::to_string(i) + " has a NaN or infinite coordinate");

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

std::string assimp_format_id(const std::string& ext) {
  if (ext == "obj") return "objnomtl";  // no side file whose name would carry the temporary name
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
  if (ext == "off") {
    write_atomically(path, [&](const fs::path& tmp) { write_off(tmp, mesh); });
    return;
  }
  const std::string format = assimp_format_id(ext);
  if (format.empty())
    throw InputError(path.string() + ": unknown output format '." + ext +
                     "' (use .off, .obj, .ply, .stl, .gltf, .glb, ...)");
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
  write_atomically(path, [&](const fs::path& tmp) {
    Assimp::Exporter exporter;
    if (exporter.Export(&scene, format, tmp.string()) != aiReturn_SUCCESS) {
      std::string why = exporter.GetErrorString();
      std::replace(why.begin(), why.end(), '\n', ' ');
      throw InputError(path.string() + ": cannot write: " + why);
    }
  });
}

}  // namespace squeeze
