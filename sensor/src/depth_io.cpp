// The one place that talks to libpng, the TUM RGB-D folder format and numbered frame folders.
#include "nbv/sensor/depth_io.hpp"

#include <png.h>

#include <algorithm>
#include <cmath>
#include <csetjmp>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <memory>
#include <optional>
#include <sstream>
#include <string>

namespace nbv::sensor {

namespace fs = std::filesystem;

namespace {

/// libpng reports errors through a callback that must not return: it keeps the message and
/// jumps back to the setjmp of the call.
struct PngErrors {
  std::string message;
  static void onError(png_structp png, png_const_charp text) {
    static_cast<PngErrors*>(png_get_error_ptr(png))->message = text != nullptr ? text : "unknown error";
    png_longjmp(png, 1);
  }
  static void onWarning(png_structp, png_const_charp) {}
};

using File = std::unique_ptr<FILE, int (*)(FILE*)>;

File openFile(const fs::path& path, const char* mode) {
  File file(std::fopen(path.c_str(), mode), &std::fclose);
  if (!file) throw FileError(path, std::string("cannot open for ") + (mode[0] == 'r' ? "reading" : "writing"));
  return file;
}

bool writeRows(png_structp png, png_infop info, FILE* file, int width, int height, int bits, const std::uint8_t* data) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_IHDR(png, info, static_cast<png_uint_32>(width), static_cast<png_uint_32>(height), bits, PNG_COLOR_TYPE_GRAY,
               PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  if (bits == 16) png_set_swap(png);  // PNG stores 16-bit samples big-endian
  const std::size_t row_bytes = static_cast<std::size_t>(width) * static_cast<std::size_t>(bits / 8);
  for (int v = 0; v < height; ++v) png_write_row(png, data + static_cast<std::size_t>(v) * row_bytes);
  png_write_end(png, nullptr);
  return true;
}

/// Writes a greyscale PNG of `bits` per pixel from `data` (row-major, host byte order).
void writeGreyPng(const fs::path& path, int width, int height, int bits, const std::uint8_t* data) {
  File file = openFile(path, "wb");
  PngErrors errors;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, &PngErrors::onError, &PngErrors::onWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  if (png == nullptr || info == nullptr) {
    png_destroy_write_struct(&png, &info);
    throw FileError(path, "cannot write PNG (out of memory)");
  }
  const bool written = writeRows(png, info, file.get(), width, height, bits, data);
  png_destroy_write_struct(&png, &info);
  if (!written) throw FileError(path, "cannot write PNG (libpng: " + errors.message + ")");
  if (std::fflush(file.get()) != 0) throw FileError(path, "write failed");
}

void requireSize(int width, int height, std::size_t values) {
  if (width <= 0 || height <= 0 || values != static_cast<std::size_t>(width) * static_cast<std::size_t>(height)) {
    throw InvalidArgument(std::to_string(values) + " pixels for an image of " + std::to_string(width) + " x " +
                          std::to_string(height));
  }
}

/// The non-comment lines of a text file, with their line numbers.
std::vector<std::pair<std::size_t, std::string>> dataLines(const fs::path& path) {
  std::error_code ec;
  if (!fs::is_regular_file(path, ec)) throw FileError(path, "no such file");
  std::ifstream in(path);
  if (!in) throw FileError(path, "cannot open for reading");
  std::vector<std::pair<std::size_t, std::string>> lines;
  std::string line;
  for (std::size_t number = 1; std::getline(in, line); ++number) {
    const std::size_t first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    lines.emplace_back(number, line);
  }
  return lines;
}

std::string at(const fs::path& path, std::size_t line) { return path.filename().string() + ":" + std::to_string(line); }

}  // namespace

namespace {

/// The image header libpng read: a plain struct, safe across libpng's longjmp.
struct PngHeader {
  png_uint_32 width = 0, height = 0;
  int bits = 0, colour = 0;
};

/// libpng's two read steps, each in its own frame with setjmp and plain data only (what a
/// longjmp may skip over); false with the message in `errors` if libpng failed.
bool readHeader(png_structp png, png_infop info, FILE* file, PngHeader* header) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_init_io(png, file);
  png_set_sig_bytes(png, 8);
  png_read_info(png, info);
  header->width = png_get_image_width(png, info);
  header->height = png_get_image_height(png, info);
  header->bits = png_get_bit_depth(png, info);
  header->colour = png_get_color_type(png, info);
  return true;
}

bool readRows(png_structp png, png_infop info, png_bytep* rows) {
  if (setjmp(png_jmpbuf(png))) return false;
  png_set_swap(png);  // 16-bit samples to host order
  png_read_update_info(png, info);
  png_read_image(png, rows);
  png_read_end(png, nullptr);
  return true;
}

}  // namespace

DepthPng readDepthPng16(const fs::path& path) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw FileError(path, "no such file");
  if (fs::is_directory(path, ec)) throw FileError(path, "is a directory, not a PNG");
  File file = openFile(path, "rb");
  png_byte signature[8] = {};
  if (std::fread(signature, 1, sizeof signature, file.get()) != sizeof signature || png_sig_cmp(signature, 0, 8) != 0) {
    throw FileError(path, "not a PNG file");
  }
  PngErrors errors;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errors, &PngErrors::onError, &PngErrors::onWarning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  const auto release = [&] { png_destroy_read_struct(&png, &info, nullptr); };
  if (png == nullptr || info == nullptr) {
    release();
    throw FileError(path, "cannot read PNG (out of memory)");
  }
  PngHeader header;
  if (!readHeader(png, info, file.get(), &header)) {
    release();
    throw FileError(path, "truncated or corrupt PNG (libpng: " + errors.message + ")");
  }
  std::string problem;
  if (header.colour != PNG_COLOR_TYPE_GRAY) {
    problem = "a colour or alpha PNG; a depth image is 16-bit greyscale";
  } else if (header.bits != 16) {
    problem = "a " + std::to_string(header.bits) + "-bit PNG; a depth image is 16-bit greyscale";
  } else if (static_cast<std::uint64_t>(header.width) * header.height > (std::uint64_t{1} << 28)) {
    problem = "a PNG of " + std::to_string(header.width) + " x " + std::to_string(header.height) +
              " pixels, too large for a depth image";
  }
  if (!problem.empty()) {
    release();
    throw FileError(path, "is " + problem);
  }
  DepthPng image;
  image.width = static_cast<int>(header.width);
  image.height = static_cast<int>(header.height);
  image.values.resize(static_cast<std::size_t>(header.width) * header.height);
  std::vector<png_bytep> rows(header.height);
  for (png_uint_32 v = 0; v < header.height; ++v) {
    rows[v] = reinterpret_cast<png_bytep>(image.values.data() + static_cast<std::size_t>(v) * header.width);
  }
  const bool read = readRows(png, info, rows.data());
  release();
  if (!read) throw FileError(path, "truncated or corrupt PNG (libpng: " + errors.message + ")");
  return image;
}

void writeDepthPng16(const fs::path& path, int width, int height, std::span<const std::uint16_t> values) {
  requireSize(width, height, values.size());
  writeGreyPng(path, width, height, 16, reinterpret_cast<const std::uint8_t*>(values.data()));
}

void writeGreyPng8(const fs::path& path, int width, int height, std::span<const std::uint8_t> values) {
  requireSize(width, height, values.size());
  writeGreyPng(path, width, height, 8, values.data());
}

namespace {

/// The numbers of one pose line: `count` finite values, `fields` naming them in the message,
/// and nothing after them. \throws FileError naming the file and line.
std::vector<double> poseNumbers(const fs::path& path, std::size_t number, const std::string& line, std::size_t count,
                                const char* fields) {
  std::istringstream tokens(line);
  std::vector<double> v;
  std::string token;
  while (tokens >> token) {
    char* end = nullptr;
    const double x = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0') {
      throw FileError(path, "line " + std::to_string(number) + ": expected " + fields + "; '" + token + "' is not a number");
    }
    v.push_back(x);
  }
  if (v.size() != count) {
    throw FileError(path, "line " + std::to_string(number) + ": expected " + fields + " (" + std::to_string(count) +
                              " numbers), got " + std::to_string(v.size()));
  }
  for (const double x : v) {
    if (!std::isfinite(x)) throw FileError(path, "line " + std::to_string(number) + ": a value is not finite: " + line);
  }
  return v;
}

/// T_world_camera of tx ty tz qx qy qz qw at `v` (the quaternion normalised).
Eigen::Isometry3d poseOf(const fs::path& path, std::size_t number, const double* v) {
  const Eigen::Quaterniond q(v[6], v[3], v[4], v[5]);
  if (!(q.norm() > 1e-9)) throw FileError(path, "line " + std::to_string(number) + ": zero quaternion");
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.linear() = q.normalized().toRotationMatrix();
  T.translation() = Eigen::Vector3d(v[0], v[1], v[2]);
  return T;
}

/// The last run of digits in a file's stem ("frame_0042" -> 42), if any.
std::optional<unsigned long long> frameNumber(const fs::path& file) {
  const std::string stem = file.stem().string();
  const std::size_t last = stem.find_last_of("0123456789");
  if (last == std::string::npos) return std::nullopt;
  std::size_t first = last;
  while (first > 0 && std::isdigit(static_cast<unsigned char>(stem[first - 1]))) --first;
  if (last - first >= 18) return std::nullopt;  // no frame count is that large
  return std::stoull(stem.substr(first, last - first + 1));
}

}  // namespace

std::vector<TumFrame> readFrameFolder(const fs::path& folder, const fs::path& poses) {
  std::error_code ec;
  if (!fs::is_directory(folder, ec)) throw FileError(folder, "is not a folder of depth images");
  std::vector<std::pair<unsigned long long, fs::path>> images;
  for (const fs::directory_entry& entry : fs::directory_iterator(folder, ec)) {
    std::error_code entry_ec;  // an entry that cannot be read (a broken link) is no image
    if (!entry.is_regular_file(entry_ec) || entry.path().extension() != ".png") continue;
    const auto n = frameNumber(entry.path());
    if (!n) throw FileError(entry.path(), "has no frame number in its name (the frames are ordered by it)");
    images.emplace_back(*n, entry.path());
  }
  if (ec) throw FileError(folder, "cannot be listed: " + ec.message());
  if (images.empty()) throw FileError(folder, "holds no .png depth image");
  std::sort(images.begin(), images.end());
  for (std::size_t i = 1; i < images.size(); ++i) {
    if (images[i].first == images[i - 1].first) {
      throw FileError(images[i].second, "has the frame number of " + images[i - 1].second.filename().string());
    }
  }
  std::vector<TumFrame> frames;
  for (const auto& [number, line] : dataLines(poses)) {
    const std::vector<double> v = poseNumbers(poses, number, line, 7, "tx ty tz qx qy qz qw");
    if (frames.size() == images.size()) {
      throw FileError(poses, "line " + std::to_string(number) + ": more poses than the " + std::to_string(images.size()) +
                                 " images of " + folder.string());
    }
    TumFrame frame;
    frame.timestamp = static_cast<double>(frames.size());
    frame.depth_file = images[frames.size()].second;
    frame.T_world_camera = poseOf(poses, number, v.data());
    frames.push_back(frame);
  }
  if (frames.size() != images.size()) {
    throw FileError(poses, "holds " + std::to_string(frames.size()) + " poses for the " + std::to_string(images.size()) +
                               " images of " + folder.string() + " (one pose per image, in frame order)");
  }
  return frames;
}

std::vector<TumFrame> readTumSequence(const fs::path& folder, double max_offset_s) {
  const fs::path depth_list = folder / "depth.txt", pose_list = folder / "groundtruth.txt";
  struct Pose {
    double t;
    Eigen::Isometry3d T;
  };
  std::vector<Pose> poses;
  for (const auto& [number, line] : dataLines(pose_list)) {
    const std::vector<double> v = poseNumbers(pose_list, number, line, 8, "timestamp tx ty tz qx qy qz qw");
    if (!poses.empty() && !(v[0] > poses.back().t)) {
      throw FileError(pose_list, "line " + std::to_string(number) + ": timestamp " + std::to_string(v[0]) +
                                     " is not after the line before (poses must be in increasing time)");
    }
    poses.push_back({v[0], poseOf(pose_list, number, v.data() + 1)});
  }
  if (poses.empty()) throw FileError(pose_list, "holds no pose");
  std::vector<TumFrame> frames;
  for (const auto& [number, line] : dataLines(depth_list)) {
    std::istringstream fields(line);
    TumFrame frame;
    std::string file;
    if (!(fields >> frame.timestamp >> file) || !std::isfinite(frame.timestamp)) {
      throw FileError(depth_list, "line " + std::to_string(number) + ": expected timestamp path");
    }
    if (!frames.empty() && !(frame.timestamp > frames.back().timestamp)) {
      throw FileError(depth_list, "line " + std::to_string(number) + ": timestamp " + std::to_string(frame.timestamp) +
                                      " is not after the line before (frames must be in increasing time)");
    }
    frame.depth_file = folder / file;
    std::error_code ec;
    if (!fs::is_regular_file(frame.depth_file, ec)) {
      throw FileError(frame.depth_file, "no such depth image (" + at(depth_list, number) + ")");
    }
    // SEMANTICS.md "Real sensor input": the pose with the nearest timestamp, within 20 ms.
    const auto after = std::lower_bound(poses.begin(), poses.end(), frame.timestamp,
                                        [](const Pose& p, double t) { return p.t < t; });
    const Pose* nearest = nullptr;
    if (after != poses.end()) nearest = &*after;
    if (after != poses.begin() && (nearest == nullptr || frame.timestamp - (after - 1)->t <= nearest->t - frame.timestamp)) {
      nearest = &*(after - 1);
    }
    if (std::abs(nearest->t - frame.timestamp) > max_offset_s) {
      std::ostringstream text;
      text << std::fixed << std::setprecision(6) << "line " << number << ": frame at " << frame.timestamp
           << " s has no pose within " << std::defaultfloat << max_offset_s * 1e3 << std::fixed
           << " ms in groundtruth.txt (nearest: " << nearest->t << " s)";
      throw FileError(depth_list, text.str());
    }
    frame.T_world_camera = nearest->T;
    frames.push_back(frame);
  }
  if (frames.empty()) throw FileError(depth_list, "lists no depth image");
  return frames;
}

void writeTumSequence(const fs::path& folder, const std::vector<DepthPng>& depths,
                      const std::vector<Eigen::Isometry3d>& T_world_cameras, double t0, double dt) {
  if (depths.size() != T_world_cameras.size()) {
    throw InvalidArgument(std::to_string(depths.size()) + " depth images for " + std::to_string(T_world_cameras.size()) + " poses");
  }
  fs::create_directories(folder / "depth");
  std::ofstream depth_list(folder / "depth.txt"), pose_list(folder / "groundtruth.txt");
  if (!depth_list) throw FileError(folder / "depth.txt", "cannot write");
  if (!pose_list) throw FileError(folder / "groundtruth.txt", "cannot write");
  depth_list << "# depth images: timestamp path (16-bit PNG, 5000 per metre as TUM RGB-D)\n";
  pose_list << "# poses of the camera: timestamp tx ty tz qx qy qz qw (T_world_camera)\n";
  depth_list << std::fixed << std::setprecision(6);
  pose_list << std::setprecision(17);
  for (std::size_t i = 0; i < depths.size(); ++i) {
    char name[32];
    std::snprintf(name, sizeof name, "depth/%06zu.png", i);
    writeDepthPng16(folder / name, depths[i].width, depths[i].height, depths[i].values);
    const double t = t0 + dt * static_cast<double>(i);
    const Eigen::Quaterniond q(T_world_cameras[i].linear());
    const Eigen::Vector3d p = T_world_cameras[i].translation();
    depth_list << t << ' ' << name << '\n';
    pose_list << std::fixed << std::setprecision(6) << t << std::defaultfloat << std::setprecision(17) << ' ' << p.x() << ' '
              << p.y() << ' ' << p.z() << ' ' << q.x() << ' ' << q.y() << ' ' << q.z() << ' ' << q.w() << '\n';
  }
  if (!depth_list.flush()) throw FileError(folder / "depth.txt", "write failed");
  if (!pose_list.flush()) throw FileError(folder / "groundtruth.txt", "write failed");
}

}  // namespace nbv::sensor
