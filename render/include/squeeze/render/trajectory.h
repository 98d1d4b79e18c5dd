// squeeze::render — reading a trajectory written by `squeeze simulate` or `squeeze replay`
// (format: scenes/README.md, "Trajectory format").
#pragma once
#include <Eigen/Core>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include "squeeze/meshing/tet_mesh.h"

namespace squeeze::fem {
struct Scene;
}

namespace squeeze::render {

/// One object of a trajectory (index.json `objects[]`).
struct TrajectoryObject {
  std::string name;
  bool robot = false, rigid = false;
  std::filesystem::path rest_mesh;  // absolute path of its rest tet mesh (world coordinates, m)
  int vertices = 0, tets = 0;       // of the rest tet mesh
  int offset = 0;                   // first vertex of this object in a frame
};

/// A trajectory folder: its index, and the frames read on demand.
struct Trajectory {
  std::filesystem::path dir;         // the trajectory/ folder itself
  std::filesystem::path scene;       // scene file recorded in the index (absolute)
  double fps = 30;                   // frames per second of the trajectory
  int frames = 0;                    // count (frame k at t = k / fps)
  int frame_vertices = 0;            // vertices per frame, all objects
  std::string frame_file;            // printf pattern relative to dir, e.g. "frames/%06d.bin"
  std::optional<double> floor;       // m
  std::vector<TrajectoryObject> objects;

  /// Duration (s): (frames - 1) / fps.
  double duration() const { return frames > 1 ? (frames - 1) / fps : 0.0; }
  /// Path of frame k.
  std::filesystem::path frame_path(int k) const;
  /// Positions of every vertex of frame k: X #frame_vertices by 3 (m), objects in order.
  /// Throws InputError ("FRAME: problem") if the file is missing, has the wrong size, or holds a
  /// NaN or infinite coordinate.
  void read_frame(int k, Eigen::MatrixX3d& X) const;
  /// The rest tet mesh of object i (world coordinates). Throws InputError.
  meshing::TetMesh rest_mesh(int i) const;
};

/// Opens a trajectory: `path` is the output folder of `squeeze simulate` (holding trajectory/ and
/// metrics.csv) or the trajectory/ folder itself. Throws InputError ("PATH: problem") if there is
/// no index.json, it is not a squeeze-trajectory of version 1, or a field is missing or invalid.
Trajectory load_trajectory(const std::filesystem::path& path);

/// Checks that `traj` is a trajectory of `scene`: the same objects (names, in order, rigid or not)
/// with the same coarse meshes (vertex and tet counts; rest positions equal to the scene's coarse
/// mesh under the object's transform, to 1e-6 of its size). The coarse meshes come from
/// fem::object_tet_mesh (cached). Throws InputError ("TRAJECTORY: not a trajectory of SCENE: why").
void check_trajectory_matches_scene(const Trajectory& traj, const fem::Scene& scene);

}  // namespace squeeze::render
