// The one place that talks to libpng, and the TUM RGB-D folder format.
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

std::vector<TumFrame> readTumSequence(const fs::path& folder, double max_offset_s) {
  const fs::path depth_list = folder / "depth.txt", pose_list = folder / "groundtruth.txt";
  struct Pose {
    double t;
    Eigen::Isometry3d T;
  };
  std::vector<Pose> poses;
  for (const auto& [number, line] : dataLines(pose_list)) {
    std::istringstream fields(line);
    double v[8];
    for (double& x : v) {
      std::string token;
      char* end = nullptr;
      if (fields >> token) x = std::strtod(token.c_str(), &end);
      if (end == nullptr || *end != '\0') {
        throw FileError(pose_list, "line " + std::to_string(number) + ": expected timestamp tx ty tz qx qy qz qw");
      }
    }
    for (const double x : v) {
      if (!std::isfinite(x)) throw FileError(pose_list, "line " + std::to_string(number) + ": a value is not finite: " + line);
    }
    const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
    if (!(q.norm() > 1e-9)) throw FileError(pose_list, "line " + std::to_string(number) + ": zero quaternion");
    if (!poses.empty() && !(v[0] > poses.back().t)) {
      throw FileError(pose_list, "line " + std::to_string(number) + ": timestamp " + std::to_string(v[0]) +
                                     " is not after the line before (poses must be in increasing time)");
    }
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() = q.normalized().toRotationMatrix();
    T.translation() = Eigen::Vector3d(v[1], v[2], v[3]);
    poses.push_back({v[0], T});
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
