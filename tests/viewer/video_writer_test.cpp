// FragmentedMp4Writer, --video's .mp4: what it writes reads back with OpenCV (frames, size, rate, order),
// a video cut short before it was finished still plays up to its last fragment, and a full disk or a
// folder that is not there is named.
#include "tachi/viewer/video_writer.hpp"

#include "scratch_dir.hpp"
#include "tachi/common/disk_full.hpp"

#include <gtest/gtest.h>
#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include <sys/resource.h>

#include <cmath>
#include <csignal>
#include <filesystem>
#include <vector>

using tachi::viewer::FragmentedMp4Writer;

namespace {
constexpr double kFps = 30.0;
const cv::Size kSize{160, 120};

// Frame k: a grey background of level 2k (its number, readable after lossy coding) and a white square
// moving across it, so consecutive frames differ as a rendered cloth's do.
cv::Mat numbered_frame(int k, cv::Size size = kSize) {
  cv::Mat image(size, CV_8UC3, cv::Scalar::all(2 * k));
  cv::rectangle(image, cv::Rect((3 * k) % (size.width - 20), size.height / 2, 20, 20), cv::Scalar::all(255), cv::FILLED);
  return image;
}

// The frame number a decoded frame shows (its top band's grey level over 2).
int number_of(const cv::Mat& frame) {
  return static_cast<int>(std::lround(cv::mean(frame(cv::Rect(0, 0, frame.cols, 40)))[1] / 2.0));
}

struct ReadBack {
  bool opened = false;
  std::vector<int> numbers;  // each decoded frame's number
  cv::Size size;
  double fps = 0.0;
  double reported_count = 0.0;
};

ReadBack read_back(const std::filesystem::path& file) {
  ReadBack r;
  cv::VideoCapture capture(file.string());
  r.opened = capture.isOpened();
  if (!r.opened) return r;
  r.fps = capture.get(cv::CAP_PROP_FPS);
  r.reported_count = capture.get(cv::CAP_PROP_FRAME_COUNT);
  for (cv::Mat frame; capture.read(frame);) {
    r.size = frame.size();
    r.numbers.push_back(number_of(frame));
  }
  return r;
}

bool in_order_from_zero(const std::vector<int>& numbers) {
  for (std::size_t i = 0; i < numbers.size(); ++i)
    if (std::abs(numbers[i] - static_cast<int>(i)) > 1) return false;
  return true;
}
}  // namespace

TEST(FragmentedMp4Writer, AFinishedVideoHasEveryFrameInOrderAtItsSizeAndRate) {
  const tachi::test::ScratchDir dir{"video_writer_whole"};
  const auto file = dir / "run.mp4";
  FragmentedMp4Writer writer{file.string(), kFps, kSize};
  EXPECT_EQ(writer.codec(), "libx264") << "Debian's libavcodec has libx264";
  for (int k = 0; k < 90; ++k) writer.write(numbered_frame(k));
  writer.finish();
  writer.finish();  // a second finish does nothing
  EXPECT_EQ(writer.frames_written(), 90U);

  const auto r = read_back(file);
  ASSERT_TRUE(r.opened) << file;
  EXPECT_EQ(r.numbers.size(), 90U);
  // What the container reports: OpenCV estimates the count from the duration (rounding it), so it is
  // allowed one frame either way.
  EXPECT_NEAR(r.reported_count, 90.0, 1.0);
  EXPECT_EQ(r.size, kSize);
  EXPECT_DOUBLE_EQ(r.fps, kFps);
  EXPECT_TRUE(in_order_from_zero(r.numbers)) << "frame k shows k: each time stamp is its number over the rate";
}

// A kill (SIGKILL, the launcher's death, a power loss) leaves what reached the file: a copy taken while
// the writer is still open is that file. 3.5 s were written; with a keyframe every second, the complete
// fragments hold at least the first 2 s even with frames still inside the encoder.
TEST(FragmentedMp4Writer, AVideoCutShortBeforeItWasFinishedPlaysUpToItsLastFragment) {
  const tachi::test::ScratchDir dir{"video_writer_cut"};
  const auto file = dir / "run.mp4";
  const auto cut = dir / "killed.mp4";
  FragmentedMp4Writer writer{file.string(), kFps, kSize};
  for (int k = 0; k < 105; ++k) writer.write(numbered_frame(k));
  std::filesystem::copy_file(file, cut);

  const auto r = read_back(cut);
  ASSERT_TRUE(r.opened) << "an unfinished video opens";
  EXPECT_GE(r.numbers.size(), 60U) << "at least 2 s of the 3.5 s written";
  EXPECT_LE(r.numbers.size(), 105U);
  EXPECT_EQ(r.size, kSize);
  EXPECT_TRUE(in_order_from_zero(r.numbers));

  writer.finish();
  EXPECT_EQ(read_back(file).numbers.size(), 105U) << "and the writer, finished, has every frame";
}

TEST(FragmentedMp4Writer, TheDestructorFinishesTheVideo) {
  const tachi::test::ScratchDir dir{"video_writer_raii"};
  const auto file = dir / "run.mp4";
  {
    FragmentedMp4Writer writer{file.string(), kFps, kSize};
    for (int k = 0; k < 40; ++k) writer.write(numbered_frame(k));
    FragmentedMp4Writer moved = std::move(writer);  // the video goes with the move
    for (int k = 40; k < 45; ++k) moved.write(numbered_frame(k));
  }
  const auto r = read_back(file);
  EXPECT_EQ(r.numbers.size(), 45U);
  EXPECT_TRUE(in_order_from_zero(r.numbers));
}

TEST(FragmentedMp4Writer, AnOddSideLosesItsLastPixelsNotItsPicture) {
  const tachi::test::ScratchDir dir{"video_writer_odd"};
  const auto file = dir / "odd.mp4";
  {
    FragmentedMp4Writer writer{file.string(), kFps, {161, 121}};
    EXPECT_EQ(writer.frame_size(), kSize);
    for (int k = 0; k < 10; ++k) writer.write(numbered_frame(k, {161, 121}));
  }
  const auto r = read_back(file);
  EXPECT_EQ(r.numbers.size(), 10U);
  EXPECT_EQ(r.size, kSize);
  EXPECT_TRUE(in_order_from_zero(r.numbers));
}

TEST(FragmentedMp4Writer, AFolderThatIsNotThereIsNamed) {
  try {
    FragmentedMp4Writer writer{"/nonexistent-tachi-folder/run.mp4", kFps, kSize};
    FAIL() << "opened";
  } catch (const std::runtime_error& e) {
    EXPECT_NE(std::string(e.what()).find("cannot open /nonexistent-tachi-folder/run.mp4 for writing"), std::string::npos) << e.what();
  }
}

// /dev/full answers every write with ENOSPC, as a filled disk does: here the header already.
TEST(FragmentedMp4Writer, AFullDiskIsDiskFullNamingTheFile) {
  ASSERT_TRUE(std::filesystem::exists("/dev/full"));
  try {
    FragmentedMp4Writer writer{"/dev/full", kFps, kSize};
    for (int k = 0; k < 300; ++k) writer.write(numbered_frame(k));
    writer.finish();
    FAIL() << "10 s of video written to /dev/full";
  } catch (const tachi::common::DiskFull& e) {
    EXPECT_EQ(e.file(), "/dev/full");
  }
}

namespace {
// A file size limit for this process while it lives: writes past it fail with EFBIG (SIGXFSZ ignored).
class FileSizeLimit {
 public:
  explicit FileSizeLimit(rlim_t bytes) {
    previous_signal_ = std::signal(SIGXFSZ, SIG_IGN);
    getrlimit(RLIMIT_FSIZE, &previous_);
    rlimit limit = previous_;
    limit.rlim_cur = bytes;
    setrlimit(RLIMIT_FSIZE, &limit);
  }
  ~FileSizeLimit() {
    setrlimit(RLIMIT_FSIZE, &previous_);
    std::signal(SIGXFSZ, previous_signal_);
  }
  FileSizeLimit(const FileSizeLimit&) = delete;
  FileSizeLimit& operator=(const FileSizeLimit&) = delete;

 private:
  rlimit previous_{};
  void (*previous_signal_)(int) = SIG_DFL;
};
}  // namespace

// A write that fails once the video runs (here: past a 64 KB file size limit) throws naming the file,
// and the writer neither writes nor throws again (its destructor leaves the failed file alone).
TEST(FragmentedMp4Writer, AWriteFailingMidRunIsAnErrorNamingTheFile) {
  const tachi::test::ScratchDir dir{"video_writer_efbig"};
  const auto file = dir / "run.mp4";
  cv::Mat noise(kSize, CV_8UC3);
  std::string error;
  {
    FragmentedMp4Writer writer{file.string(), kFps, kSize};
    const FileSizeLimit limit{64 * 1024};
    try {
      for (int k = 0; k < 300; ++k) {
        cv::randu(noise, 0, 256);  // incompressible: a fragment of it is far over 64 KB
        writer.write(noise);
      }
      writer.finish();
    } catch (const tachi::common::DiskFull& e) {
      FAIL() << "not a full disk: " << e.what();
    } catch (const std::runtime_error& e) {
      error = e.what();
    }
    EXPECT_THROW(writer.write(noise), std::logic_error);
  }
  EXPECT_NE(error.find(file.string()), std::string::npos) << error;
}
