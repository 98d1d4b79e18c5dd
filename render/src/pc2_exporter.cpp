#include "squeeze/render/export_formats.h"
#include "squeeze/render/pc2_exporter.h"

#include <cstring>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"
#include "squeeze/meshing/surface_io.h"

namespace squeeze::render {
namespace fs = std::filesystem;

static_assert(sizeof(float) == 4 && sizeof(std::int32_t) == 4, "point caches need 32-bit float and int");

namespace {

// The 4 bytes of `v` in big-endian order (MDD) or little-endian (pc2), whatever the host's order.
template <class T>
void put(std::vector<char>& out, T v, bool big_endian) {
  static_assert(sizeof(T) == 4, "4-byte fields only");
  std::uint32_t u;
  std::memcpy(&u, &v, 4);
  for (int i = 0; i < 4; ++i) out.push_back(static_cast<char>((u >> (big_endian ? 24 - 8 * i : 8 * i)) & 0xff));
}

}  // namespace

PointCacheWriter::PointCacheWriter(Format format, const fs::path& path, int points, int samples, float start_frame,
                                   double fps)
    : format_(format), path_(path), tmp_(temporary_sibling(path)), points_(points), samples_(samples) {
  std::vector<char> header;
  if (format == Format::pc2) {
    const char magic[12] = "POINTCACHE2";  // with its terminating zero
    header.assign(magic, magic + 12);
    put(header, std::int32_t{1}, false);
    put(header, std::int32_t{points}, false);
    put(header, start_frame, false);
    put(header, 1.0f, false);  // sample rate: one sample per frame
    put(header, std::int32_t{samples}, false);
  } else {
    put(header, std::int32_t{samples}, true);
    put(header, std::int32_t{points}, true);
    for (int i = 0; i < samples; ++i) put(header, static_cast<float>((start_frame + i) / fps), true);
  }
  file_ = std::fopen(tmp_.c_str(), "wb");
  if (!file_) throw InputError(path.string() + ": cannot open for writing");
  write_or_throw(header.data(), header.size());
  row_.resize(static_cast<size_t>(points) * 3);
}

PointCacheWriter::~PointCacheWriter() {
  if (file_) {
    std::fclose(file_);
    std::error_code ec;
    fs::remove(tmp_, ec);
  }
}

void PointCacheWriter::write_or_throw(const void* data, size_t bytes) {
  if (std::fwrite(data, 1, bytes, file_) == bytes) return;
  std::fclose(file_);
  file_ = nullptr;
  std::error_code ec;
  fs::remove(tmp_, ec);
  throw InputError(path_.string() + ": write failed (disk full?)");
}

void PointCacheWriter::append(const Eigen::MatrixX3d& V) {
  if (!file_ || V.rows() != points_) throw InputError(path_.string() + ": a sample has the wrong number of points");
  for (Eigen::Index i = 0; i < V.rows(); ++i)
    for (int c = 0; c < 3; ++c) row_[static_cast<size_t>(i * 3 + c)] = static_cast<float>(V(i, c));
  std::vector<char> bytes;
  bytes.reserve(row_.size() * 4);
  for (float x : row_) put(bytes, x, format_ == Format::mdd);
  write_or_throw(bytes.data(), bytes.size());
  ++written_;
}

void PointCacheWriter::close() {
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

Pc2Writer::Pc2Writer(const fs::path& path, int points, int samples, float start_frame, float sample_rate)
    : PointCacheWriter(Format::pc2, path, points, samples, start_frame, 30) {
  if (sample_rate != 1.0f) throw InputError(path.string() + ": only a sample rate of 1 (one sample per frame) is written");
}

void PointCacheExporter::begin(const ExportContext& c) {
  writers_.clear();
  const char* ext = format_ == PointCacheWriter::Format::pc2 ? ".pc2" : ".mdd";
  for (const ExportObject& ob : c.objects) {
    meshing::save_surface(c.folder / (ob.name + ".obj"), meshing::SurfaceMesh{ob.rest, ob.faces});
    writers_.push_back(std::make_unique<PointCacheWriter>(format_, c.folder / (ob.name + ext),
                                                          static_cast<int>(ob.rest.rows()), c.frame_count,
                                                          static_cast<float>(c.first_frame), c.fps));
  }
}

void PointCacheExporter::frame(int, double, const std::vector<ExportState>& states) {
  for (size_t b = 0; b < writers_.size(); ++b) writers_[b]->append(states[b].surface);
}

void PointCacheExporter::finish() {
  for (auto& w : writers_) w->close();
}

ExportFormat pc2_export_format() {
  return {"pc2", "rest OBJ + Blender point cache per object",
          [] { return std::make_unique<PointCacheExporter>(PointCacheWriter::Format::pc2); }};
}

ExportFormat mdd_export_format() {
  return {"mdd", "rest OBJ + MDD point cache per object (Blender, 3ds Max, LightWave, Houdini)",
          [] { return std::make_unique<PointCacheExporter>(PointCacheWriter::Format::mdd); }};
}

}  // namespace squeeze::render
