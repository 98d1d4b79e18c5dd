#include "squeeze/render/export_formats.h"
#include "squeeze/render/pc2_exporter.h"

#include <cstring>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_io.h"

namespace squeeze::render {
namespace fs = std::filesystem;

static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4, "pc2 needs 32-bit float and int");

Pc2Writer::Pc2Writer(const fs::path& path, int points, int samples, float start_frame, float sample_rate)
    : path_(path), tmp_(temporary_sibling(path)), points_(points), samples_(samples) {
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) throw InputError(path.string() + ": cannot open for writing");
  char header[32] = {0};
  std::memcpy(header, "POINTCACHE2", 12);  // with its terminating zero
  const std::int32_t version = 1, p = points, s = samples;
  std::memcpy(header + 12, &version, 4);
  std::memcpy(header + 16, &p, 4);
  std::memcpy(header + 20, &start_frame, 4);
  std::memcpy(header + 24, &sample_rate, 4);
  std::memcpy(header + 28, &s, 4);
  if (std::fwrite(header, 1, 32, file_) != 32) {
    std::fclose(file_);
    file_ = nullptr;
    std::error_code ec;
    fs::remove(tmp_, ec);
    throw InputError(path.string() + ": write failed");
  }
  row_.resize(static_cast<size_t>(points) * 3);
}

Pc2Writer::~Pc2Writer() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void Pc2Writer::append(const Eigen::MatrixX3d& V) {
  if (!file_ || V.rows() != points_) throw InputError(path_.string() + ": a sample has the wrong number of points");
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int c = 0; c < 3; ++c) row_[static_cast<size_t>(i * 3 + c)] = static_cast<float>(V(i, c));
  if (std::fwrite(row_.data(), sizeof(float), row_.size(), file_) != row_.size())
    throw InputError(path_.string() + ": write failed (disk full?)");
  ++written_;
}

void Pc2Writer::close() {
  if (!file_) return;
  if (written_ != samples_)
    throw InputError(path_.string() + ": " + std::to_string(written_) + " samples written, " +
                     std::to_string(samples_) + " announced");
  const bool bad = std::fflush(file_) != 0 || std::ferror(file_);
  const int closed = std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  if (bad || closed != 0) {
    fs::remove(tmp_, ec);
    throw InputError(path_.string() + ": write failed (disk full?)");
  }
  fs::rename(tmp_, path_, ec);
  if (ec) {
    fs::remove(tmp_, ec);
    throw InputError(path_.string() + ": cannot move into place");
  }
}

void Pc2Exporter::begin(const ExportContext& c) {
  writers_.clear();
  for (const ExportObject& ob : c.objects) {
    meshing::save_surface(c.folder / (ob.name + ".obj"), meshing::SurfaceMesh{ob.rest, ob.faces});
    writers_.push_back(std::make_unique<Pc2Writer>(c.folder / (ob.name + ".pc2"), static_cast<int>(ob.rest.rows()),
                                                   c.frame_count, static_cast<float>(c.first_frame), 1.0f));
  }
}

void Pc2Exporter::frame(int, double, const std::vector<ExportState>& states) {
  for (size_t b = 0; b < writers_.size(); ++b) writers_[b]->append(states[b].surface);
}

void Pc2Exporter::finish() {
  for (auto& w : writers_) w->close();
}

ExportFormat pc2_export_format() {
  return {"pc2", "rest OBJ + Blender point cache per object", [] { return std::make_unique<Pc2Exporter>(); }};
}

}  // namespace squeeze::render
