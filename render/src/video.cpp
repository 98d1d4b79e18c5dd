#include "squeeze/render/video.h"

#include <spdlog/spdlog.h>

#include <system_error>

#include "squeeze/common/atomic_file.h"
#include "squeeze/common/error.h"

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/opt.h>
#include <libswscale/swscale.h>
}

namespace squeeze::render {
namespace fs = std::filesystem;

namespace {

const AVCodec* h264_encoder() {
  if (const AVCodec* c = avcodec_find_encoder_by_name("libx264")) return c;
  return avcodec_find_encoder(AV_CODEC_ID_H264);
}

std::string av_message(int code) {
  char buf[AV_ERROR_MAX_STRING_SIZE] = {0};
  av_strerror(code, buf, sizeof(buf));
  return buf;
}

}  // namespace

bool video_available(std::string* why) {
  if (h264_encoder()) return true;
  if (why) *why = "this FFmpeg (libavcodec) has no H.264 encoder (Debian's libavcodec59 has libx264)";
  return false;
}

struct VideoWriter::Impl {
  fs::path path, tmp;
  int width = 0, height = 0;  // of the images
  int encoded_width = 0, encoded_height = 0;
  AVFormatContext* format = nullptr;
  AVCodecContext* codec = nullptr;
  AVStream* stream = nullptr;
  AVFrame* frame = nullptr;
  AVPacket* packet = nullptr;
  SwsContext* scale = nullptr;
  int frames = 0;
  bool open_file = false, finished = false;

  [[noreturn]] void fail(const std::string& what, int code) const {
    throw InputError(path.string() + ": " + what + (code ? ": " + av_message(code) : std::string()));
  }

  // Sends `f` (null: flush) and writes every packet the encoder gives back.
  void encode(AVFrame* f) {
    int r = avcodec_send_frame(codec, f);
    if (r < 0) fail("video encoding failed", r);
    while ((r = avcodec_receive_packet(codec, packet)) == 0) {
      av_packet_rescale_ts(packet, codec->time_base, stream->time_base);
      packet->stream_index = stream->index;
      const int w = av_interleaved_write_frame(format, packet);
      if (w < 0) fail("write failed (disk full?)", w);
    }
    if (r != AVERROR(EAGAIN) && r != AVERROR_EOF) fail("video encoding failed", r);
  }

  ~Impl() {
    sws_freeContext(scale);
    av_packet_free(&packet);
    av_frame_free(&frame);
    avcodec_free_context(&codec);
    if (format) {
      if (open_file) avio_closep(&format->pb);
      avformat_free_context(format);
    }
    if (!finished && !tmp.empty()) {
      std::error_code ec;
      fs::remove(tmp, ec);
    }
  }
};

VideoWriter::VideoWriter(const fs::path& path, int width, int height, double fps) : impl_(std::make_unique<Impl>()) {
  Impl& v = *impl_;
  v.path = path;
  v.width = width;
  v.height = height;
  v.encoded_width = width & ~1;
  v.encoded_height = height & ~1;
  if (v.encoded_width < 16 || v.encoded_height < 16) v.fail("the frames are too small for a video", 0);
  if (!(fps > 0 && fps <= 10000)) v.fail("frames per second must be in (0, 10000]", 0);
  if (v.encoded_width != width || v.encoded_height != height)
    spdlog::warn("{}: H.264 needs even sides: the video is {}x{} (the frames are {}x{})", path.string(), v.encoded_width,
                 v.encoded_height, width, height);
  std::string why;
  if (!video_available(&why)) v.fail(why, 0);
  av_log_set_level(spdlog::get_level() <= spdlog::level::debug ? AV_LOG_INFO : AV_LOG_ERROR);
  check_output_directory(path);
  v.tmp = temporary_sibling(path);

  int r = avformat_alloc_output_context2(&v.format, nullptr, "mp4", v.tmp.c_str());
  if (r < 0 || !v.format) v.fail("cannot create an MP4", r);
  const AVCodec* encoder = h264_encoder();
  v.stream = avformat_new_stream(v.format, nullptr);
  v.codec = avcodec_alloc_context3(encoder);
  v.frame = av_frame_alloc();
  v.packet = av_packet_alloc();
  if (!v.stream || !v.codec || !v.frame || !v.packet) v.fail("out of memory", 0);
  const AVRational rate = av_d2q(fps, 100000);
  v.codec->width = v.encoded_width;
  v.codec->height = v.encoded_height;
  v.codec->time_base = av_inv_q(rate);
  v.codec->framerate = rate;
  v.codec->pix_fmt = AV_PIX_FMT_YUV420P;
  v.codec->gop_size = std::max(1, static_cast<int>(fps));
  if (v.format->oformat->flags & AVFMT_GLOBALHEADER) v.codec->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
  av_opt_set(v.codec->priv_data, "preset", "fast", 0);
  av_opt_set(v.codec->priv_data, "crf", "20", 0);
  r = avcodec_open2(v.codec, encoder, nullptr);
  if (r < 0) v.fail("cannot open the H.264 encoder", r);
  r = avcodec_parameters_from_context(v.stream->codecpar, v.codec);
  if (r < 0) v.fail("cannot set the stream's parameters", r);
  v.stream->time_base = v.codec->time_base;
  v.stream->avg_frame_rate = rate;
  r = avio_open(&v.format->pb, v.tmp.c_str(), AVIO_FLAG_WRITE);
  if (r < 0) v.fail("cannot open for writing", r);
  v.open_file = true;
  r = avformat_write_header(v.format, nullptr);
  if (r < 0) v.fail("cannot write the MP4 header", r);
  v.frame->format = AV_PIX_FMT_YUV420P;
  v.frame->width = v.encoded_width;
  v.frame->height = v.encoded_height;
  r = av_frame_get_buffer(v.frame, 0);
  if (r < 0) v.fail("out of memory", r);
  v.scale = sws_getContext(v.encoded_width, v.encoded_height, AV_PIX_FMT_RGBA, v.encoded_width, v.encoded_height,
                           AV_PIX_FMT_YUV420P, SWS_BICUBIC, nullptr, nullptr, nullptr);
  if (!v.scale) v.fail("cannot convert RGBA to YUV", 0);
}

VideoWriter::~VideoWriter() = default;

void VideoWriter::add(const Image& image) {
  Impl& v = *impl_;
  if (v.finished) v.fail("a frame after finish()", 0);
  if (image.width != v.width || image.height != v.height)
    v.fail("a frame of " + std::to_string(image.width) + "x" + std::to_string(image.height) + " in a " +
               std::to_string(v.width) + "x" + std::to_string(v.height) + " video",
           0);
  const int r = av_frame_make_writable(v.frame);
  if (r < 0) v.fail("out of memory", r);
  // The image's rows run bottom to top: start at its top row (the last) with a negative stride.
  const int stride = 4 * image.width;
  const std::uint8_t* top = image.pixels.data() + static_cast<size_t>(image.height - 1) * stride;
  const std::uint8_t* src[1] = {top};
  const int src_stride[1] = {-stride};
  sws_scale(v.scale, src, src_stride, 0, v.encoded_height, v.frame->data, v.frame->linesize);
  v.frame->pts = v.frames++;
  v.encode(v.frame);
}

void VideoWriter::finish() {
  Impl& v = *impl_;
  if (v.finished) return;
  v.encode(nullptr);
  int r = av_write_trailer(v.format);
  if (r < 0) v.fail("write failed (disk full?)", r);
  r = avio_closep(&v.format->pb);
  v.open_file = false;
  if (r < 0) v.fail("write failed (disk full?)", r);
  std::error_code ec;
  fs::rename(v.tmp, v.path, ec);
  if (ec) v.fail("cannot move into place: " + ec.message(), 0);
  v.finished = true;
}

int VideoWriter::frames() const { return impl_->frames; }

}  // namespace squeeze::render
