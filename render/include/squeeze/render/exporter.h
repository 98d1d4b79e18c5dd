// squeeze::render — the Exporter interface: one class per export format (pc2, obj, ply, vtu, …),
// driven by render_trajectory over the frames it renders.
//
//   begin(context)            once, before the first frame: create files, write what is per object
//   frame(k, t, states)       per output frame k of the range, in order: the deformed meshes
//   finish()                  once, after the last frame: complete and rename into place
//
// Atomicity: every file is written under a temporary name (squeeze::write_atomically,
// temporary_sibling) and renamed into place only when complete — per-frame files at once, files
// spanning frames (a point cache, an index) by finish(). An exporter destroyed without finish()
// (an exception mid-way, from any exporter or the renderer) removes its temporaries: no
// half-written file is ever left. The formats are listed in export_formats.h.
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <string>
#include <vector>

namespace squeeze::render {

/// One object of the scene as exporters see it (scene order).
struct ExportObject {
  std::string name;               // the scene's object name (files are named after it)
  Eigen::MatrixX3d rest;          // high-resolution surface vertices at rest (world, m): exactly the
                                  // rendered surface's, each used by a face (none unreferenced)
  Eigen::MatrixX3i faces;         // its triangles, outwards when the surface is closed
  Eigen::MatrixX4i tets;          // the coarse tet mesh (indices into ExportState::coarse)
  Eigen::Vector3f colour{0.8f, 0.8f, 0.8f};  // the render colour, linear RGB in [0, 1]
  bool rigid = false;             // a rigid object (its surface moves rigidly)
};

/// What an export gets before the first frame.
struct ExportContext {
  std::filesystem::path folder;       // OUT/export: exists and is writable; an exporter may add subfolders
  std::vector<ExportObject> objects;  // every object of the scene, in scene order
  int first_frame = 0, last_frame = 0;  // inclusive range of output frames that frame() will get
  int frame_count = 0;                // last_frame - first_frame + 1
  double fps = 30;                    // output frames per simulated second: frame k is at t = k / fps
};

/// One object in one frame; the references are valid during the frame() call only.
struct ExportState {
  const Eigen::MatrixX3d& surface;  // deformed high-resolution surface, rows as ExportObject::rest (m)
  const Eigen::MatrixX3d& coarse;   // deformed coarse tet-mesh vertices (m)
};

/// One export format. Member functions throw InputError (one line naming the file) on a write
/// failure; after an exception the exporter is only destroyed.
class Exporter {
 public:
  virtual ~Exporter() = default;
  /// Called once before the first frame.
  virtual void begin(const ExportContext& context) = 0;
  /// Called for every output frame k of the range, in order, at time t = k / fps (s);
  /// `states[i]` is context.objects[i].
  virtual void frame(int k, double t, const std::vector<ExportState>& states) = 0;
  /// Called once after the last frame: completes the files that span frames and renames them
  /// into place.
  virtual void finish() = 0;
};

/// The name of per-frame files: PREFIX + k zero-padded to 5 digits + EXTENSION, e.g.
/// frame_file_name("ball_", 7, ".obj") == "ball_00007.obj" (PNG frames: "frame_00007.png").
std::string frame_file_name(const std::string& prefix, int k, const std::string& extension);

}  // namespace squeeze::render
