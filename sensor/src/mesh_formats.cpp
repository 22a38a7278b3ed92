#include "mesh_formats.hpp"

#include "ply_reader.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <vector>

namespace nbv::sensor::detail {

namespace fs = std::filesystem;

void MeshBuilder::addVertex(double x, double y, double z, const std::string& where) {
  if (mesh_.vertices.size() >= static_cast<std::size_t>(std::numeric_limits<int>::max())) {
    throw MeshFileError(path_, where + ": more vertices than an int index can hold");
  }
  // Checked in single precision: 1e39 is a finite double but no float (found by fuzz_mesh).
  const Eigen::Vector3f v(static_cast<float>(x), static_cast<float>(y), static_cast<float>(z));
  if (!v.allFinite()) {
    throw MeshFileError(path_, where + ": vertex " + std::to_string(mesh_.vertices.size()) +
                                   " is not finite in single precision");
  }
  mesh_.vertices.push_back(v);
}

void MeshBuilder::addPolygon(const std::uint64_t* indices, std::size_t count, const std::string& where) {
  if (count < 3) throw MeshFileError(path_, where + ": a face needs 3 vertices, this one has " + std::to_string(count));
  for (std::size_t k = 0; k < count; ++k) {
    if (indices[k] >= mesh_.vertices.size()) {
      throw MeshFileError(path_, where + ": vertex index " + std::to_string(indices[k]) + " is out of range (" +
                                     std::to_string(mesh_.vertices.size()) + " vertices)");
    }
  }
  for (std::size_t k = 1; k + 1 < count; ++k) {  // a fan around the first vertex
    const Eigen::Vector3i tri(static_cast<int>(indices[0]), static_cast<int>(indices[k]),
                              static_cast<int>(indices[k + 1]));
    const Eigen::Vector3f& a = mesh_.vertices[static_cast<std::size_t>(tri[0])];
    const Eigen::Vector3f& b = mesh_.vertices[static_cast<std::size_t>(tri[1])];
    const Eigen::Vector3f& c = mesh_.vertices[static_cast<std::size_t>(tri[2])];
    if (tri[0] == tri[1] || tri[1] == tri[2] || tri[0] == tri[2] || (b - a).cross(c - a).squaredNorm() == 0.0f) {
      ++report_.degenerate_dropped;
      continue;
    }
    mesh_.triangles.push_back(tri);
  }
}

TriangleMesh MeshBuilder::finish() {
  if (mesh_.triangles.empty()) throw MeshFileError(path_, "mesh has no (non-degenerate) triangles");
  return std::move(mesh_);
}

namespace {

/// Whitespace-separated words of the text lines of a file; '#' starts a comment (OFF, OBJ).
class TextLines {
 public:
  TextLines(const std::string& bytes, bool hash_comments) : bytes_(bytes), hash_comments_(hash_comments) {}

  /// The next line with at least one word, or false at the end of the file.
  bool next(std::vector<std::string>& words) {
    while (pos_ < bytes_.size()) {
      std::size_t eol = bytes_.find('\n', pos_);
      if (eol == std::string::npos) eol = bytes_.size();
      std::size_t end = eol;
      if (hash_comments_) {  // a comment runs to the end of its line (search this line only)
        end = static_cast<std::size_t>(std::find(bytes_.begin() + static_cast<std::ptrdiff_t>(pos_),
                                                 bytes_.begin() + static_cast<std::ptrdiff_t>(eol), '#') -
                                       bytes_.begin());
      }
      ++line_;
      words.clear();
      std::size_t i = pos_;
      while (i < end) {
        while (i < end && std::isspace(static_cast<unsigned char>(bytes_[i]))) ++i;
        std::size_t j = i;
        while (j < end && !std::isspace(static_cast<unsigned char>(bytes_[j]))) ++j;
        if (j > i) words.emplace_back(bytes_, i, j - i);
        i = j;
      }
      pos_ = eol + 1;
      if (!words.empty()) return true;
    }
    return false;
  }
  std::string where() const { return "line " + std::to_string(line_); }

 private:
  const std::string& bytes_;
  bool hash_comments_;
  std::size_t pos_ = 0;
  int line_ = 0;
};

/// A whole word as a number (nan and inf spellings included: the builder refuses them by line).
bool parseNumber(const std::string& word, double& value) {
  char* end = nullptr;
  value = std::strtod(word.c_str(), &end);
  return !word.empty() && end == word.c_str() + word.size();
}

bool parseCount(const std::string& word, std::uint64_t& value) {
  const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), value);
  return ec == std::errc() && end == word.data() + word.size();
}

double number(const std::string& word, const TextLines& lines, const fs::path& path) {
  double value = 0.0;
  if (!parseNumber(word, value)) throw MeshFileError(path, lines.where() + ": '" + word + "' is not a number");
  return value;
}

}  // namespace

// OFF (and COFF, NOFF, ...): "OFF", "V F E", V vertex lines "x y z [extras]", F face lines
// "n i_1 ... i_n [colour]". The counts are checked against the file size before anything is
// allocated: each vertex line takes at least 6 bytes ("0 0 0\n"), each face at least 8.
TriangleMesh readOff(const std::string& bytes, const fs::path& path, MeshLoadReport& report) {
  TextLines lines(bytes, /*hash_comments=*/true);
  std::vector<std::string> words;
  if (!lines.next(words) || words[0].size() < 3 || words[0].compare(words[0].size() - 3, 3, "OFF") != 0) {
    throw MeshFileError(path, "not an OFF file (no 'OFF' keyword on the first line)");
  }
  if (words.size() == 1 && !lines.next(words)) throw MeshFileError(path, "OFF header has no vertex and face counts");
  const std::size_t first = words[0].find("OFF") != std::string::npos ? 1 : 0;
  std::uint64_t vertices = 0, faces = 0;
  if (words.size() < first + 2 || !parseCount(words[first], vertices) || !parseCount(words[first + 1], faces)) {
    throw MeshFileError(path, lines.where() + ": OFF header counts are not counts");
  }
  if (static_cast<long double>(vertices) * 6.0L + static_cast<long double>(faces) * 8.0L >
      static_cast<long double>(bytes.size())) {
    throw MeshFileError(path, "OFF header claims " + std::to_string(vertices) + " vertices and " +
                                  std::to_string(faces) + " faces, more than the file can hold");
  }
  MeshBuilder builder(path, report);
  for (std::uint64_t v = 0; v < vertices; ++v) {
    if (!lines.next(words)) {
      throw MeshFileError(path, "ends after " + std::to_string(v) + " of " + std::to_string(vertices) + " vertices");
    }
    if (words.size() < 3) throw MeshFileError(path, lines.where() + ": a vertex needs x y z");
    builder.addVertex(number(words[0], lines, path), number(words[1], lines, path), number(words[2], lines, path),
                      lines.where());
  }
  std::vector<std::uint64_t> polygon;
  for (std::uint64_t f = 0; f < faces; ++f) {
    if (!lines.next(words)) {
      throw MeshFileError(path, "ends after " + std::to_string(f) + " of " + std::to_string(faces) + " faces");
    }
    std::uint64_t n = 0;
    if (!parseCount(words[0], n) || n >= words.size()) {  // the count and n indices on the line
      throw MeshFileError(path, lines.where() + ": a face is 'n i_1 ... i_n'");
    }
    polygon.resize(n);
    for (std::uint64_t k = 0; k < n; ++k) {
      if (!parseCount(words[k + 1], polygon[k])) {
        throw MeshFileError(path, lines.where() + ": '" + words[k + 1] + "' is not a vertex index");
      }
    }
    builder.addPolygon(polygon.data(), polygon.size(), lines.where());
  }
  return builder.finish();
}

// OBJ: "v x y z [w]" and "f a b c ..." with a = i, i/t, i//n or i/t/n (1-based, negative
// counts back from the last vertex read); every other statement is ignored.
TriangleMesh readObj(const std::string& bytes, const fs::path& path, MeshLoadReport& report) {
  TextLines lines(bytes, /*hash_comments=*/true);
  std::vector<std::string> words;
  std::vector<std::uint64_t> polygon;
  MeshBuilder builder(path, report);
  while (lines.next(words)) {
    if (words[0] == "v") {
      if (words.size() < 4) throw MeshFileError(path, lines.where() + ": a vertex needs x y z");
      builder.addVertex(number(words[1], lines, path), number(words[2], lines, path), number(words[3], lines, path),
                        lines.where());
    } else if (words[0] == "f") {
      polygon.clear();
      for (std::size_t k = 1; k < words.size(); ++k) {
        const std::string& word = words[k];
        std::int64_t index = 0;
        const auto [end, ec] = std::from_chars(word.data(), word.data() + word.size(), index);
        if (ec != std::errc() || (end != word.data() + word.size() && *end != '/') || index == 0) {
          throw MeshFileError(path, lines.where() + ": '" + word + "' is not a vertex reference");
        }
        const auto count = static_cast<std::int64_t>(builder.vertexCount());
        const std::int64_t zero_based = index > 0 ? index - 1 : count + index;
        if (zero_based < 0 || zero_based >= count) {
          throw MeshFileError(path, lines.where() + ": vertex " + word + " is out of range (" + std::to_string(count) +
                                        " vertices so far)");
        }
        polygon.push_back(static_cast<std::uint64_t>(zero_based));
      }
      builder.addPolygon(polygon.data(), polygon.size(), lines.where());
    }
  }
  return builder.finish();
}

// STL: binary (80-byte header, uint32 count, 50 bytes per triangle) when the size fits the
// count exactly, else ASCII ("solid", facets of "outer loop", 3 "vertex x y z", "endloop",
// "endfacet", "endsolid").
TriangleMesh readStl(const std::string& bytes, const fs::path& path, MeshLoadReport& report) {
  MeshBuilder builder(path, report);
  std::uint32_t count = 0;
  if (bytes.size() >= 84) std::memcpy(&count, bytes.data() + 80, 4);  // little endian, as the format
  const bool binary = bytes.size() >= 84 && bytes.size() == 84 + 50 * static_cast<std::uint64_t>(count);
  if (binary) {
    for (std::uint32_t t = 0; t < count; ++t) {
      float values[12];
      std::memcpy(values, bytes.data() + 84 + 50 * static_cast<std::size_t>(t), sizeof values);
      const std::string where = "triangle " + std::to_string(t);
      for (int k = 1; k <= 3; ++k) builder.addVertex(values[3 * k], values[3 * k + 1], values[3 * k + 2], where);
      const std::uint64_t tri[3] = {builder.vertexCount() - 3, builder.vertexCount() - 2, builder.vertexCount() - 1};
      builder.addPolygon(tri, 3, where);
    }
    return builder.finish();
  }
  if (bytes.compare(0, 5, "solid") != 0) {
    if (bytes.size() < 84) throw MeshFileError(path, "not an STL file: no 'solid' and shorter than the 84-byte binary header");
    throw MeshFileError(path, "binary STL claims " + std::to_string(count) + " triangles (" +
                                  std::to_string(84 + 50 * static_cast<std::uint64_t>(count)) + " bytes) but has " +
                                  std::to_string(bytes.size()) + " bytes");
  }
  TextLines lines(bytes, /*hash_comments=*/false);
  std::vector<std::string> words;
  std::vector<std::uint64_t> loop;
  bool in_loop = false, ended = false;
  while (lines.next(words)) {
    if (ended) throw MeshFileError(path, lines.where() + ": text after 'endsolid'");
    if (words[0] == "outer") {
      in_loop = true;
      loop.clear();
    } else if (words[0] == "vertex") {
      if (!in_loop || words.size() != 4) throw MeshFileError(path, lines.where() + ": 'vertex x y z' outside a loop");
      builder.addVertex(number(words[1], lines, path), number(words[2], lines, path), number(words[3], lines, path),
                        lines.where());
      loop.push_back(builder.vertexCount() - 1);
    } else if (words[0] == "endloop") {
      if (!in_loop) throw MeshFileError(path, lines.where() + ": 'endloop' without 'outer loop'");
      builder.addPolygon(loop.data(), loop.size(), lines.where());
      in_loop = false;
    } else if (words[0] == "endsolid") {
      if (in_loop) throw MeshFileError(path, lines.where() + ": 'endsolid' inside a loop");
      ended = true;
    }
  }
  if (!ended) throw MeshFileError(path, "ASCII STL has no 'endsolid' (truncated?)");
  return builder.finish();
}

TriangleMesh readPlyMesh(const std::string& bytes, const fs::path& path, MeshLoadReport& report) {
  PlyData ply;
  try {
    ply = parsePly(bytes, /*with_faces=*/true);
  } catch (const PlyProblem& problem) {
    throw MeshFileError(path, problem.what());
  }
  if (ply.polygon_sizes.empty()) throw MeshFileError(path, "PLY file has no faces");
  MeshBuilder builder(path, report);
  for (std::size_t v = 0; v < ply.vertices.size(); ++v) {
    const Eigen::Vector3f& p = ply.vertices[v];
    builder.addVertex(p.x(), p.y(), p.z(), "vertex " + std::to_string(v));
  }
  std::size_t offset = 0;
  for (std::size_t f = 0; f < ply.polygon_sizes.size(); ++f) {
    builder.addPolygon(ply.polygon_indices.data() + offset, ply.polygon_sizes[f], "face " + std::to_string(f));
    offset += ply.polygon_sizes[f];
  }
  return builder.finish();
}

}  // namespace nbv::sensor::detail
