#include "ply_reader.hpp"

#include <algorithm>
#include <array>
#include <bit>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <sstream>

namespace nbv::sensor::detail {

namespace {

enum class PlyFormat { Ascii, BinaryLittle, BinaryBig };

struct PlyType {
  const char* names[2];
  int bytes;
};
constexpr std::array<PlyType, 8> kPlyTypes{{{{"char", "int8"}, 1},
                                            {{"uchar", "uint8"}, 1},
                                            {{"short", "int16"}, 2},
                                            {{"ushort", "uint16"}, 2},
                                            {{"int", "int32"}, 4},
                                            {{"uint", "uint32"}, 4},
                                            {{"float", "float32"}, 4},
                                            {{"double", "float64"}, 8}}};

std::optional<int> plyTypeIndex(const std::string& name) {
  for (int i = 0; i < static_cast<int>(kPlyTypes.size()); ++i) {
    if (name == kPlyTypes[i].names[0] || name == kPlyTypes[i].names[1]) return i;
  }
  return std::nullopt;
}

struct PlyProperty {
  std::string name;
  int type = 0;             // index into kPlyTypes
  int list_count_type = -1; // >= 0 for list properties
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
};

/// Reads binary PLY scalars from a byte buffer, bounds-checked.
class BinaryReader {
 public:
  BinaryReader(const std::string& bytes, std::size_t pos, bool big_endian)
      : bytes_(bytes), pos_(pos), swap_(big_endian != (std::endian::native == std::endian::big)) {}

  double read(int type) {
    const int n = kPlyTypes[static_cast<std::size_t>(type)].bytes;
    if (bytes_.size() - pos_ < static_cast<std::size_t>(n)) {
      throw PlyProblem("truncated binary data after byte " + std::to_string(pos_));
    }
    unsigned char raw[8];
    std::memcpy(raw, bytes_.data() + pos_, static_cast<std::size_t>(n));
    pos_ += static_cast<std::size_t>(n);
    if (swap_) std::reverse(raw, raw + n);
    switch (type) {
      case 0: { std::int8_t v; std::memcpy(&v, raw, 1); return v; }
      case 1: { std::uint8_t v; std::memcpy(&v, raw, 1); return v; }
      case 2: { std::int16_t v; std::memcpy(&v, raw, 2); return v; }
      case 3: { std::uint16_t v; std::memcpy(&v, raw, 2); return v; }
      case 4: { std::int32_t v; std::memcpy(&v, raw, 4); return v; }
      case 5: { std::uint32_t v; std::memcpy(&v, raw, 4); return v; }
      case 6: { float v; std::memcpy(&v, raw, 4); return v; }
      default: { double v; std::memcpy(&v, raw, 8); return v; }
    }
  }
  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  const std::string& bytes_;
  std::size_t pos_;
  bool swap_;
};

/// Reads whitespace-separated ASCII PLY values, tracking the line for error messages.
class AsciiReader {
 public:
  AsciiReader(const std::string& bytes, std::size_t pos, int line) : bytes_(bytes), pos_(pos), line_(line) {}

  double read() {
    while (pos_ < bytes_.size() && std::isspace(static_cast<unsigned char>(bytes_[pos_]))) {
      if (bytes_[pos_] == '\n') ++line_;
      ++pos_;
    }
    if (pos_ >= bytes_.size()) {
      throw PlyProblem("line " + std::to_string(line_) + ": unexpected end of file");
    }
    std::size_t end = pos_;
    while (end < bytes_.size() && !std::isspace(static_cast<unsigned char>(bytes_[end]))) ++end;
    const std::string token = bytes_.substr(pos_, end - pos_);
    pos_ = end;
    // strtod accepts nan/inf spellings, which point clouds use for invalid pixels.
    char* parsed_end = nullptr;
    const double value = std::strtod(token.c_str(), &parsed_end);
    if (parsed_end != token.c_str() + token.size()) {
      throw PlyProblem("line " + std::to_string(line_) + ": '" + token +
                                      "' is not a number");
    }
    return value;
  }
  std::size_t remaining() const { return bytes_.size() - pos_; }

 private:
  const std::string& bytes_;
  std::size_t pos_;
  int line_;
};

struct PlyHeader {
  PlyFormat format = PlyFormat::Ascii;
  std::vector<PlyElement> elements;
  std::size_t body_offset = 0;
  int body_line = 0;
};

PlyHeader parsePlyHeader(const std::string& bytes) {
  PlyHeader header;
  std::size_t pos = 0;
  int line_number = 0;
  bool have_format = false;
  auto fail = [&](const std::string& problem) -> PlyProblem {
    return PlyProblem("line " + std::to_string(line_number) + ": " + problem);
  };
  while (true) {
    const std::size_t eol = bytes.find('\n', pos);
    if (eol == std::string::npos) {
      throw PlyProblem(line_number == 0 ? "not a PLY file (no 'ply' line)"
                                                  : "header has no 'end_header' (truncated?)");
    }
    std::string line = bytes.substr(pos, eol - pos);
    if (!line.empty() && line.back() == '\r') line.pop_back();
    pos = eol + 1;
    ++line_number;
    std::istringstream words(line);
    std::string keyword;
    words >> keyword;
    if (line_number == 1) {
      if (keyword != "ply") throw PlyProblem("not a PLY file (first line is not 'ply')");
      continue;
    }
    if (keyword.empty() || keyword == "comment" || keyword == "obj_info") continue;
    if (keyword == "format") {
      std::string format, version;
      words >> format >> version;
      if (format == "ascii") {
        header.format = PlyFormat::Ascii;
      } else if (format == "binary_little_endian") {
        header.format = PlyFormat::BinaryLittle;
      } else if (format == "binary_big_endian") {
        header.format = PlyFormat::BinaryBig;
      } else {
        throw fail("unknown format '" + format + "'");
      }
      have_format = true;
    } else if (keyword == "element") {
      PlyElement element;
      std::string count;
      words >> element.name >> count;
      const auto [end, ec] = std::from_chars(count.data(), count.data() + count.size(), element.count);
      if (element.name.empty() || ec != std::errc() || end != count.data() + count.size()) {
        throw fail("malformed element line '" + line + "'");
      }
      header.elements.push_back(element);
    } else if (keyword == "property") {
      if (header.elements.empty()) throw fail("property before any element");
      PlyProperty property;
      std::string type;
      words >> type;
      if (type == "list") {
        std::string count_type, item_type;
        words >> count_type >> item_type;
        const auto count_index = plyTypeIndex(count_type);
        const auto item_index = plyTypeIndex(item_type);
        if (!count_index || !item_index || *count_index >= 6) {
          throw fail("malformed list property '" + line + "'");
        }
        property.list_count_type = *count_index;
        property.type = *item_index;
      } else {
        const auto index = plyTypeIndex(type);
        if (!index) throw fail("unknown property type '" + type + "'");
        property.type = *index;
      }
      words >> property.name;
      if (property.name.empty()) throw fail("property without a name");
      header.elements.back().properties.push_back(property);
    } else if (keyword == "end_header") {
      if (!have_format) throw fail("end_header before any 'format' line");
      header.body_offset = pos;
      header.body_line = line_number + 1;
      return header;
    } else {
      throw fail("unknown header keyword '" + keyword + "'");
    }
  }
}

/// Smallest number of bytes one record of `element` takes in the body (for refusing absurd
/// counts before allocating): binary sizes, or 2 characters per ASCII value.
std::uint64_t minimumRecordBytes(const PlyElement& element, PlyFormat format) {
  std::uint64_t bytes = 0;
  for (const PlyProperty& p : element.properties) {
    const int type = p.list_count_type >= 0 ? p.list_count_type : p.type;
    bytes += format == PlyFormat::Ascii ? 2 : static_cast<std::uint64_t>(kPlyTypes[static_cast<std::size_t>(type)].bytes);
  }
  return std::max<std::uint64_t>(bytes, 1);
}

template <class Reader, class ReadValue>
PlyData readBody(const PlyHeader& header, Reader& reader, ReadValue read_value, bool with_faces) {
  PlyData data;
  bool have_vertices = false;
  for (const PlyElement& element : header.elements) {
    const bool is_vertex = element.name == "vertex" && !have_vertices;
    const bool is_face = with_faces && element.name == "face";
    int axis_of[64];
    if (element.properties.size() > 64) throw PlyProblem("element '" + element.name + "' has too many properties");
    if (is_vertex) {
      int found = 0;
      for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const std::string& name = element.properties[i].name;
        axis_of[i] = name == "x" ? 0 : name == "y" ? 1 : name == "z" ? 2 : -1;
        if (axis_of[i] >= 0) {
          if (element.properties[i].list_count_type >= 0) {
            throw PlyProblem("vertex property '" + name + "' is a list");
          }
          found |= 1 << axis_of[i];
        }
      }
      if (found != 7) throw PlyProblem("vertex element lacks x, y or z");
    }
    std::size_t index_list = element.properties.size();
    if (is_face) {
      for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const PlyProperty& p = element.properties[i];
        if (p.list_count_type >= 0 && (p.name == "vertex_indices" || p.name == "vertex_index")) index_list = i;
      }
      if (index_list == element.properties.size()) throw PlyProblem("face element has no vertex_indices list");
    }
    // Refuse counts the file cannot hold before allocating anything.
    if (element.count > reader.remaining() / minimumRecordBytes(element, header.format)) {
      throw PlyProblem("element '" + element.name + "' claims " + std::to_string(element.count) +
                       " records, more than the file can hold (truncated?)");
    }
    if (is_vertex) data.vertices.reserve(element.count);
    if (is_face) data.polygon_sizes.reserve(element.count);
    for (std::uint64_t r = 0; r < element.count; ++r) {
      Eigen::Vector3f p = Eigen::Vector3f::Zero();
      for (std::size_t i = 0; i < element.properties.size(); ++i) {
        const PlyProperty& property = element.properties[i];
        if (property.list_count_type >= 0) {
          const double items = read_value(property.list_count_type);
          if (!(items >= 0.0) || items > static_cast<double>(reader.remaining())) {
            throw PlyProblem("invalid list length in element '" + element.name + "'");
          }
          const bool keep = is_face && i == index_list;
          for (auto k = static_cast<std::uint64_t>(items); k > 0; --k) {
            const double value = read_value(property.type);
            if (!keep) continue;
            if (!(value >= 0.0) || value != std::floor(value)) {
              throw PlyProblem("face " + std::to_string(r) + " has vertex index " + std::to_string(value));
            }
            data.polygon_indices.push_back(static_cast<std::uint64_t>(value));
          }
          if (keep) data.polygon_sizes.push_back(static_cast<std::uint32_t>(items));
          continue;
        }
        const double value = read_value(property.type);
        if (is_vertex && axis_of[i] >= 0) p[axis_of[i]] = static_cast<float>(value);
      }
      if (is_vertex) data.vertices.push_back(p);
    }
    if (is_vertex) {
      have_vertices = true;
      if (!with_faces) return data;  // later elements (faces, ...) are not needed
    }
  }
  if (!have_vertices) throw PlyProblem("no 'vertex' element");
  return data;
}

}  // namespace

PlyData parsePly(const std::string& bytes, bool with_faces) {
  if (bytes.empty()) throw PlyProblem("file is empty");
  const PlyHeader header = parsePlyHeader(bytes);
  if (header.format == PlyFormat::Ascii) {
    AsciiReader reader(bytes, header.body_offset, header.body_line);
    return readBody(header, reader, [&reader](int) { return reader.read(); }, with_faces);
  }
  BinaryReader reader(bytes, header.body_offset, header.format == PlyFormat::BinaryBig);
  return readBody(header, reader, [&reader](int type) { return reader.read(type); }, with_faces);
}

}  // namespace nbv::sensor::detail
