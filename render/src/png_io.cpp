#include "squeeze/render/png_io.h"

#include <png.h>
#include <zlib.h>

#include <cstdio>
#include <memory>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

namespace squeeze::render {
namespace fs = std::filesystem;

namespace {
struct File {
  FILE* f = nullptr;
  ~File() {
    if (f) std::fclose(f);
  }
};
[[noreturn]] void png_fail(png_structp png, png_const_charp msg) {
  std::string* err = static_cast<std::string*>(png_get_error_ptr(png));
  if (err) *err = msg;
  png_longjmp(png, 1);
}
void png_warn(png_structp, png_const_charp) {}
}  // namespace

void write_png(const fs::path& path, const Image& image, int compression) {
  if (image.width <= 0 || image.height <= 0 ||
      image.pixels.size() != static_cast<size_t>(image.width) * image.height * 4)
    throw std::invalid_argument("write_png: image size and pixel count disagree");
  write_atomically(path, [&](const fs::path& tmp) {
    File file;
    file.f = std::fopen(tmp.c_str(), "wb");
    if (!file.f) throw InputError(path.string() + ": cannot open for writing");
    std::string error;
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &error, png_fail, png_warn);
    png_infop info = png ? png_create_info_struct(png) : nullptr;
    if (!png || !info) {
      png_destroy_write_struct(&png, nullptr);
      throw InputError(path.string() + ": out of memory for the PNG encoder");
    }
    std::vector<png_bytep> rows(static_cast<size_t>(image.height));
    if (setjmp(png_jmpbuf(png))) {
      png_destroy_write_struct(&png, &info);
      throw InputError(path.string() + ": PNG write failed: " + error);
    }
    png_init_io(png, file.f);
    png_set_compression_level(png, compression);
    png_set_filter(png, 0, PNG_FILTER_SUB);
    png_set_compression_strategy(png, Z_RLE);  // runs of background: smaller and as fast as level 1
    png_set_IHDR(png, info, static_cast<png_uint_32>(image.width), static_cast<png_uint_32>(image.height), 8,
                 PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    png_write_info(png, info);
    png_set_filler(png, 0, PNG_FILLER_AFTER);  // input is RGBA: drop the alpha byte
    for (int y = 0; y < image.height; ++y)
      rows[static_cast<size_t>(y)] = const_cast<png_bytep>(image.pixels.data()) +
                                     static_cast<size_t>(image.height - 1 - y) * image.width * 4;
    png_write_image(png, rows.data());
    png_write_end(png, nullptr);
    png_destroy_write_struct(&png, &info);
    const bool bad = std::fflush(file.f) != 0 || std::ferror(file.f);
    const int closed = std::fclose(file.f);
    file.f = nullptr;
    if (bad || closed != 0) throw InputError(path.string() + ": write failed (disk full?)");
  });
}

PngImage read_png(const fs::path& path) {
  File file;
  file.f = std::fopen(path.c_str(), "rb");
  if (!file.f) throw InputError(path.string() + ": cannot open");
  unsigned char sig[8];
  if (std::fread(sig, 1, 8, file.f) != 8 || png_sig_cmp(sig, 0, 8))
    throw InputError(path.string() + ": not a valid PNG: bad signature");
  std::string error;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &error, png_fail, png_warn);
  png_infop info = png ? png_create_info_struct(png) : nullptr;
  if (!png || !info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    throw InputError(path.string() + ": out of memory for the PNG decoder");
  }
  PngImage out;
  std::vector<png_bytep> rows;
  if (setjmp(png_jmpbuf(png))) {
    png_destroy_read_struct(&png, &info, nullptr);
    throw InputError(path.string() + ": not a valid PNG: " + error);
  }
  png_init_io(png, file.f);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  png_set_expand(png);
  png_set_strip_16(png);
  png_set_gray_to_rgb(png);
  png_read_update_info(png, info);
  out.width = static_cast<int>(png_get_image_width(png, info));
  out.height = static_cast<int>(png_get_image_height(png, info));
  out.channels = png_get_channels(png, info);
  const size_t stride = png_get_rowbytes(png, info);
  out.pixels.resize(stride * static_cast<size_t>(out.height));
  rows.resize(static_cast<size_t>(out.height));
  for (int y = 0; y < out.height; ++y) rows[static_cast<size_t>(y)] = out.pixels.data() + stride * static_cast<size_t>(y);
  png_read_image(png, rows.data());
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return out;
}

PngWriter::PngWriter(int capacity, int compression)
    : capacity_(std::max(1, capacity)), compression_(compression), thread_([this] { run(); }) {}

PngWriter::~PngWriter() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  changed_.notify_all();
  if (thread_.joinable()) thread_.join();
}

void PngWriter::run() {
  for (;;) {
    Job job;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      changed_.wait(lock, [&] { return stop_ || !queue_.empty(); });
      if (queue_.empty()) return;  // stop requested and nothing left
      job = std::move(queue_.front());
      queue_.pop_front();
      busy_ = true;
    }
    changed_.notify_all();
    std::exception_ptr e;
    try {
      write_png(job.path, job.image, compression_);
    } catch (...) {
      e = std::current_exception();
    }
    {
      std::lock_guard<std::mutex> lock(mutex_);
      busy_ = false;
      if (spare_.size() < 2) spare_.push_back(std::move(job.image.pixels));
      if (e && !error_) {
        error_ = e;
        queue_.clear();
      }
    }
    changed_.notify_all();
  }
}

void PngWriter::rethrow() {
  if (error_) {
    std::exception_ptr e = error_;
    error_ = nullptr;
    std::rethrow_exception(e);
  }
}

void PngWriter::push(const fs::path& path, Image&& image) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return error_ || static_cast<int>(queue_.size()) < capacity_; });
  rethrow();
  queue_.push_back(Job{path, std::move(image)});
  lock.unlock();
  changed_.notify_all();
}

void PngWriter::recycle(Image& image) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (spare_.empty()) return;
  image.pixels = std::move(spare_.back());
  spare_.pop_back();
}

void PngWriter::finish() {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return queue_.empty() && !busy_; });
  rethrow();
}

}  // namespace squeeze::render
