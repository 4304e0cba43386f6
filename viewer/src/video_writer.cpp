#include "tachi/viewer/video_writer.hpp"

#include "tachi/common/disk_full.hpp"

#include <spdlog/spdlog.h>

extern "C" {
#include <libavcodec/avcodec.h>
#include <libavformat/avformat.h>
#include <libavutil/dict.h>
#include <libavutil/error.h>
#include <libavutil/frame.h>
#include <libavutil/log.h>
#include <libswscale/swscale.h>
}

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace tachi::viewer {
namespace {

// Each fragment starts at a keyframe and carries its own index (moof); empty_moov writes the header at
// once instead of at the close; default_base_moof makes each fragment's offsets its own, so a player
// needs nothing after the fragment to read it.
constexpr const char* kFragmentedMovFlags = "frag_keyframe+empty_moov+default_base_moof";

std::string av_error(int code) {
  char text[AV_ERROR_MAX_STRING_SIZE] = {};
  av_strerror(code, text, sizeof text);
  return text;
}

struct CloseFormat {
  void operator()(AVFormatContext* format) const {
    if (format->pb != nullptr) avio_closep(&format->pb);
    avformat_free_context(format);
  }
};
struct FreeEncoder {
  void operator()(AVCodecContext* c) const { avcodec_free_context(&c); }
};
struct FreeScaler {
  void operator()(SwsContext* s) const { sws_freeContext(s); }
};
struct FreeFrame {
  void operator()(AVFrame* f) const { av_frame_free(&f); }
};
struct FreePacket {
  void operator()(AVPacket* p) const { av_packet_free(&p); }
};
struct FreeDictionary {
  void operator()(AVDictionary* d) const { av_dict_free(&d); }
};
using Dictionary = std::unique_ptr<AVDictionary, FreeDictionary>;

Dictionary dictionary(std::initializer_list<std::pair<const char*, const char*>> entries) {
  AVDictionary* d = nullptr;
  for (const auto& [key, value] : entries) av_dict_set(&d, key, value, 0);
  return Dictionary(d);
}

// H.264 when libavcodec has libx264 (Debian's does), else MPEG-4 part 2, which every FFmpeg has.
std::unique_ptr<AVCodecContext, FreeEncoder> open_encoder(AVRational rate, cv::Size size, bool global_header) {
  std::string tried;
  for (const char* name : {"libx264", "mpeg4"}) {
    const AVCodec* codec = avcodec_find_encoder_by_name(name);
    if (codec == nullptr) {
      tried += std::string(tried.empty() ? "" : ", ") + name + ": not in this FFmpeg";
      continue;
    }
    std::unique_ptr<AVCodecContext, FreeEncoder> c(avcodec_alloc_context3(codec));
    if (!c) throw std::bad_alloc();
    c->width = size.width;
    c->height = size.height;
    c->pix_fmt = AV_PIX_FMT_YUV420P;
    c->time_base = av_inv_q(rate);
    c->framerate = rate;
    // A keyframe at least every second: a fragment ends at each, so a killed viewer loses at most the
    // last second or so (plus what the encoder still holds).
    c->gop_size = std::max(1, static_cast<int>(std::lround(av_q2d(rate))));
    if (global_header) c->flags |= AV_CODEC_FLAG_GLOBAL_HEADER;
    Dictionary options = dictionary({});
    if (std::string(name) == "libx264") {
      options = dictionary({{"preset", "veryfast"}});
    } else {
      // MPEG-4's default is 200 kbit/s whatever the size: a fixed quantiser instead (3: near-transparent).
      c->flags |= AV_CODEC_FLAG_QSCALE;
      c->global_quality = FF_QP2LAMBDA * 3;
    }
    AVDictionary* raw = options.release();
    const int rc = avcodec_open2(c.get(), codec, &raw);
    options.reset(raw);
    if (rc >= 0) return c;
    tried += std::string(tried.empty() ? "" : ", ") + name + ": " + av_error(rc);
  }
  throw std::runtime_error("no video encoder (" + tried + ")");
}

}  // namespace

struct FragmentedMp4Writer::Muxer {
  std::string path;
  cv::Size input;  // what write() takes
  cv::Size size;   // what is encoded: input made even
  std::unique_ptr<AVCodecContext, FreeEncoder> encoder;
  std::unique_ptr<AVFormatContext, CloseFormat> format;
  AVStream* stream = nullptr;
  std::unique_ptr<SwsContext, FreeScaler> scaler;
  std::unique_ptr<AVFrame, FreeFrame> frame;
  std::unique_ptr<AVPacket, FreePacket> packet;
  std::uint64_t frames = 0;
  bool writable = true;  // false once finished or failed

  [[noreturn]] void fail(int rc, const std::string& what) {
    writable = false;
    if (common::out_of_space(path, AVUNERROR(rc))) throw common::DiskFull(path);
    throw std::runtime_error(path + ": " + what + ": " + av_error(rc));
  }

  // Sends `f` (nullptr: drain) to the encoder and muxes every packet it gives back. The muxer flushes
  // its buffer to the file after each packet, so what a fragment holds is on disk once it is written.
  void encode(const AVFrame* f) {
    if (const int rc = avcodec_send_frame(encoder.get(), f); rc < 0) fail(rc, "cannot encode a frame");
    for (;;) {
      const int rc = avcodec_receive_packet(encoder.get(), packet.get());
      if (rc == AVERROR(EAGAIN) || rc == AVERROR_EOF) return;
      if (rc < 0) fail(rc, "cannot encode a frame");
      av_packet_rescale_ts(packet.get(), encoder->time_base, stream->time_base);
      packet->stream_index = stream->index;
      if (const int wrc = av_interleaved_write_frame(format.get(), packet.get()); wrc < 0) fail(wrc, "cannot write the video");
    }
  }
};

FragmentedMp4Writer::FragmentedMp4Writer(const std::string& path, double fps, cv::Size size) : muxer_(std::make_unique<Muxer>()) {
  // libx264 logs its CPU flags and statistics at AV_LOG_INFO straight to stderr, which is the viewer's log.
  static std::once_flag quiet;
  std::call_once(quiet, [] { av_log_set_level(AV_LOG_ERROR); });

  Muxer& m = *muxer_;
  m.path = path;
  m.input = size;
  m.size = cv::Size(size.width & ~1, size.height & ~1);
  const auto cannot = [&](const std::string& why) { return std::runtime_error("cannot open " + path + " for writing: " + why); };
  if (m.size.width < 2 || m.size.height < 2 || !(fps > 0.0))
    throw cannot("a " + std::to_string(size.width) + "x" + std::to_string(size.height) + " video at " + std::to_string(fps) + " fps");

  AVFormatContext* raw = nullptr;
  if (const int rc = avformat_alloc_output_context2(&raw, nullptr, "mp4", path.c_str()); rc < 0) throw cannot(av_error(rc));
  m.format.reset(raw);
  const AVRational rate = av_d2q(fps, 100000);
  try {
    m.encoder = open_encoder(rate, m.size, (m.format->oformat->flags & AVFMT_GLOBALHEADER) != 0);
  } catch (const std::runtime_error& e) {
    throw cannot(e.what());
  }
  m.stream = avformat_new_stream(m.format.get(), nullptr);
  if (m.stream == nullptr) throw std::bad_alloc();
  m.stream->time_base = m.encoder->time_base;
  m.stream->avg_frame_rate = rate;
  if (const int rc = avcodec_parameters_from_context(m.stream->codecpar, m.encoder.get()); rc < 0) throw cannot(av_error(rc));

  if (const int rc = avio_open(&m.format->pb, path.c_str(), AVIO_FLAG_WRITE); rc < 0) throw cannot(av_error(rc));
  // flush_packets: the file gets each packet the muxer gives out at once, so a finished fragment is on
  // disk, not in the I/O buffer (32 KB, which a still cloth's fragments take seconds to fill), when the
  // viewer is killed.
  Dictionary options = dictionary({{"movflags", kFragmentedMovFlags}, {"flush_packets", "1"}});
  AVDictionary* opts = options.release();
  const int rc = avformat_write_header(m.format.get(), &opts);
  options.reset(opts);
  if (rc < 0) {
    if (common::out_of_space(path, AVUNERROR(rc))) throw common::DiskFull(path);  // the header did not fit
    throw cannot(av_error(rc));
  }
  // An option the muxer did not take would leave an ordinary MP4 without a word: refuse it instead.
  if (av_dict_count(options.get()) != 0) throw cannot("the MP4 muxer ignored movflags " + std::string(kFragmentedMovFlags));

  m.scaler.reset(sws_getContext(m.size.width, m.size.height, AV_PIX_FMT_BGR24, m.size.width, m.size.height, AV_PIX_FMT_YUV420P,
                                SWS_BILINEAR, nullptr, nullptr, nullptr));
  m.frame.reset(av_frame_alloc());
  m.packet.reset(av_packet_alloc());
  if (!m.scaler || !m.frame || !m.packet) throw std::bad_alloc();
  m.frame->format = AV_PIX_FMT_YUV420P;
  m.frame->width = m.size.width;
  m.frame->height = m.size.height;
  if (const int rc2 = av_frame_get_buffer(m.frame.get(), 0); rc2 < 0) throw cannot(av_error(rc2));
}

FragmentedMp4Writer::~FragmentedMp4Writer() {
  if (!muxer_ || !muxer_->writable) return;  // moved from, finished, or failed (a failed write was reported once)
  try {
    finish();
  } catch (const std::exception& e) {
    spdlog::warn("tachi-viewer: {}", e.what());
  }
}

FragmentedMp4Writer::FragmentedMp4Writer(FragmentedMp4Writer&&) noexcept = default;
FragmentedMp4Writer& FragmentedMp4Writer::operator=(FragmentedMp4Writer&&) noexcept = default;

void FragmentedMp4Writer::write(const cv::Mat& bgr) {
  if (!muxer_ || !muxer_->writable) throw std::logic_error("a video written after it was finished, failed or moved");
  Muxer& m = *muxer_;
  if (bgr.type() != CV_8UC3 || bgr.size() != m.input)
    throw std::invalid_argument(m.path + ": a frame of another size or type than the video's");
  if (const int rc = av_frame_make_writable(m.frame.get()); rc < 0) m.fail(rc, "cannot encode a frame");
  // The source is read at the encoded (even) size with the image's own stride: an odd last column or
  // row is left out, not scaled in.
  const uint8_t* const source[] = {bgr.data};
  const int stride[] = {static_cast<int>(bgr.step[0])};
  sws_scale(m.scaler.get(), source, stride, 0, m.size.height, m.frame->data, m.frame->linesize);
  m.frame->pts = static_cast<std::int64_t>(m.frames);
  if ((m.encoder->flags & AV_CODEC_FLAG_QSCALE) != 0) m.frame->quality = m.encoder->global_quality;
  m.encode(m.frame.get());
  ++m.frames;
}

void FragmentedMp4Writer::finish() {
  if (!muxer_ || !muxer_->writable) return;
  Muxer& m = *muxer_;
  m.encode(nullptr);
  if (const int rc = av_write_trailer(m.format.get()); rc < 0) m.fail(rc, "cannot finish the video");
  if (const int rc = avio_closep(&m.format->pb); rc < 0) m.fail(rc, "cannot close the video");
  m.writable = false;
}

std::string FragmentedMp4Writer::codec() const { return muxer_->encoder->codec->name; }
cv::Size FragmentedMp4Writer::frame_size() const { return muxer_->size; }
std::uint64_t FragmentedMp4Writer::frames_written() const { return muxer_->frames; }

}  // namespace tachi::viewer
