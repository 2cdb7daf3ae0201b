// LoadMesh: Wavefront OBJ and STL (binary and ASCII) readers.

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string_view>
#include <unordered_map>

#include "core/error.h"
#include "spheres/internal_geometry.h"
#include "spheres/mesh.h"

namespace flowplan::spheres {
namespace {

using internal::NumberText;

std::string Lower(std::string_view text) {
  std::string out(text);
  for (char& c : out) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return out;
}

// The whitespace-separated words of one line.
std::vector<std::string_view> Words(std::string_view line) {
  std::vector<std::string_view> words;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    const size_t start = i;
    while (i < line.size() && !std::isspace(static_cast<unsigned char>(line[i]))) ++i;
    if (i > start) words.push_back(line.substr(start, i - start));
  }
  return words;
}

// Splits `text` into lines (without '\n' or a trailing '\r'), numbered from 1.
std::vector<std::string_view> Lines(std::string_view text) {
  std::vector<std::string_view> lines;
  size_t start = 0;
  while (start <= text.size()) {
    size_t end = text.find('\n', start);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(start, end - start);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    if (end == text.size()) break;
    start = end + 1;
  }
  return lines;
}

// A whole word as a double, locale-independent; false if it is not one.
bool ParseDouble(std::string_view word, double* value) {
  if (!word.empty() && word.front() == '+') word.remove_prefix(1);
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

bool ParseInt(std::string_view word, long long* value) {
  if (!word.empty() && word.front() == '+') word.remove_prefix(1);
  const char* end = word.data() + word.size();
  const auto result = std::from_chars(word.data(), end, *value);
  return result.ec == std::errc() && result.ptr == end;
}

// Merges corners at exactly the same position (STL stores three per triangle).
class VertexWelder {
 public:
  explicit VertexWelder(Mesh* mesh) : mesh_(mesh) {}

  int Add(const std::array<double, 3>& p) {
    Key key;
    for (int k = 0; k < 3; ++k) {
      const double x = p[k] + 0.0;  // -0.0 and 0.0 are one position
      std::memcpy(&key.bits[k], &x, sizeof(double));
    }
    const auto [it, inserted] = index_.emplace(key, static_cast<int>(mesh_->vertices.size()));
    if (inserted) mesh_->vertices.push_back(p);
    return it->second;
  }

 private:
  struct Key {
    uint64_t bits[3];
    bool operator==(const Key& other) const {
      return bits[0] == other.bits[0] && bits[1] == other.bits[1] && bits[2] == other.bits[2];
    }
  };
  struct KeyHash {
    size_t operator()(const Key& key) const {
      uint64_t h = 0x9E3779B97F4A7C15ULL;
      for (uint64_t b : key.bits) h = (h ^ b) * 0x100000001B3ULL + (h >> 29);
      return static_cast<size_t>(h);
    }
  };
  Mesh* mesh_;
  std::unordered_map<Key, int, KeyHash> index_;
};

// ---- OBJ --------------------------------------------------------------------

Mesh ReadObj(const std::string& path, std::string_view text) {
  Mesh mesh;
  struct PendingIndex {
    long long index;  // 1-based, as written
    int line;
  };
  // Faces may refer to vertices defined further down, so positive indices are
  // checked once every vertex is known.
  std::vector<std::array<PendingIndex, 3>> faces;
  const auto lines = Lines(text);
  for (size_t n = 0; n < lines.size(); ++n) {
    const int line_no = static_cast<int>(n) + 1;
    std::string_view line = lines[n];
    if (const size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    const auto words = Words(line);
    if (words.empty()) continue;
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    if (words[0] == "v") {
      const size_t numbers = words.size() - 1;
      // x y z, x y z w, x y z r g b, x y z w r g b (vertex colours).
      if (numbers < 3 || numbers > 7 || numbers == 5) {
        throw Error(where + "v: expected x y z [w], got " + std::to_string(numbers) + " numbers");
      }
      std::array<double, 3> p;
      for (size_t k = 1; k < words.size(); ++k) {
        double value;
        if (!ParseDouble(words[k], &value)) {
          throw Error(where + "v: '" + std::string(words[k]) + "' is not a number");
        }
        if (!std::isfinite(value)) {
          throw Error(where + "v: " + (k <= 3 ? "coordinate " : "number ") + std::string(words[k]) + " is not finite");
        }
        if (k <= 3) p[k - 1] = value;
      }
      mesh.vertices.push_back(p);
    } else if (words[0] == "f") {
      if (words.size() < 4) {
        throw Error(where + "f: expected at least 3 vertices, got " + std::to_string(words.size() - 1));
      }
      std::vector<PendingIndex> polygon;
      for (size_t k = 1; k < words.size(); ++k) {
        const std::string_view reference = words[k];
        const std::string_view vertex = reference.substr(0, reference.find('/'));
        long long index;
        if (!ParseInt(vertex, &index)) {
          throw Error(where + "f: '" + std::string(reference) + "' is not a vertex reference (i, i/t, i//n or i/t/n)");
        }
        const auto defined = static_cast<long long>(mesh.vertices.size());
        if (index == 0) throw Error(where + "f: vertex index 0 (OBJ indices start at 1)");
        if (index < 0) {
          if (index < -defined) {
            throw Error(where + "f: relative vertex index " + std::to_string(index) + " outside -1.." +
                        std::to_string(-defined) + " (" + std::to_string(defined) + " vertices so far)");
          }
          index = defined + index + 1;
        }
        polygon.push_back({index, line_no});
      }
      for (size_t k = 1; k + 1 < polygon.size(); ++k) faces.push_back({polygon[0], polygon[k], polygon[k + 1]});
    }
  }
  const auto count = static_cast<long long>(mesh.vertices.size());
  mesh.triangles.reserve(faces.size());
  for (const auto& face : faces) {
    std::array<int, 3> triangle;
    for (int k = 0; k < 3; ++k) {
      if (face[k].index > count) {
        throw Error(path + ":" + std::to_string(face[k].line) + ": f: vertex index " + std::to_string(face[k].index) +
                    " outside 1.." + std::to_string(count));
      }
      triangle[k] = static_cast<int>(face[k].index - 1);
    }
    mesh.triangles.push_back(triangle);
  }
  if (mesh.triangles.empty()) {
    throw Error(path + ": no triangles (no 'f' lines; " + std::to_string(count) + " vertices)");
  }
  return mesh;
}

// ---- STL --------------------------------------------------------------------

uint32_t ReadU32(const unsigned char* bytes) {
  return static_cast<uint32_t>(bytes[0]) | (static_cast<uint32_t>(bytes[1]) << 8) |
         (static_cast<uint32_t>(bytes[2]) << 16) | (static_cast<uint32_t>(bytes[3]) << 24);
}

float ReadF32(const unsigned char* bytes) {
  const uint32_t bits = ReadU32(bytes);
  float value;
  std::memcpy(&value, &bits, sizeof(value));
  return value;
}

Mesh ReadBinaryStl(const std::string& path, std::string_view data) {
  const uint64_t size = data.size();
  if (size < 84) {
    throw Error(path + ": " + std::to_string(size) +
                " bytes: too short for a binary STL (at least 84) and not an ASCII STL (starting with \"solid\")");
  }
  const auto* bytes = reinterpret_cast<const unsigned char*>(data.data());
  const uint64_t count = ReadU32(bytes + 80);
  const uint64_t expected = 84 + 50 * count;
  if (size < expected) {
    const uint64_t triangle = (size - 84) / 50;
    throw Error(path + ": byte " + std::to_string(84 + 50 * triangle) + ": triangle " + std::to_string(triangle) +
                " of " + std::to_string(count) + " is truncated (a binary STL of " + std::to_string(count) +
                " triangles has 84 + 50*" + std::to_string(count) + " = " + std::to_string(expected) +
                " bytes, the file " + std::to_string(size) + ")");
  }
  if (size > expected) {
    throw Error(path + ": byte " + std::to_string(expected) + ": " + std::to_string(size - expected) +
                " bytes after the last of the " + std::to_string(count) + " triangles the binary STL header announces");
  }
  if (count == 0) throw Error(path + ": binary STL without triangles (bytes 80..83 hold 0)");
  Mesh mesh;
  VertexWelder welder(&mesh);
  mesh.triangles.reserve(count);
  for (uint64_t t = 0; t < count; ++t) {
    const uint64_t offset = 84 + 50 * t;
    std::array<int, 3> triangle;
    for (int k = 0; k < 3; ++k) {
      std::array<double, 3> p;
      for (int c = 0; c < 3; ++c) {
        const uint64_t at = offset + 12 + 12 * k + 4 * c;
        const float value = ReadF32(bytes + at);
        if (!std::isfinite(value)) {
          throw Error(path + ": byte " + std::to_string(at) + " (triangle " + std::to_string(t) + ", corner " +
                      std::to_string(k) + "): coordinate " + NumberText(value) + " is not finite");
        }
        p[c] = value;
      }
      triangle[k] = welder.Add(p);
    }
    mesh.triangles.push_back(triangle);
  }
  return mesh;
}

Mesh ReadAsciiStl(const std::string& path, std::string_view text) {
  Mesh mesh;
  VertexWelder welder(&mesh);
  enum class State { kBeforeSolid, kInSolid, kFacet, kLoop, kEndFacet };
  State state = State::kBeforeSolid;
  std::vector<int> corners;
  const auto lines = Lines(text);
  int line_no = 0;
  for (size_t n = 0; n < lines.size(); ++n) {
    const auto words = Words(lines[n]);
    if (words.empty()) continue;
    line_no = static_cast<int>(n) + 1;  // the last line with words, for the end-of-file message
    const std::string where = path + ":" + std::to_string(line_no) + ": ";
    const std::string keyword = Lower(words[0]);
    auto expect = [&](const char* wanted) {
      throw Error(where + "expected " + wanted + ", got '" + std::string(lines[n].substr(0, 60)) + "'");
    };
    switch (state) {
      case State::kBeforeSolid:
        if (keyword != "solid") expect("'solid <name>'");
        state = State::kInSolid;
        break;
      case State::kInSolid:
        if (keyword == "endsolid") {
          state = State::kBeforeSolid;
        } else if (keyword == "facet") {
          state = State::kFacet;  // the normal is recomputed from the corners, so it is not read
        } else {
          expect("'facet normal nx ny nz' or 'endsolid'");
        }
        break;
      case State::kFacet:
        if (keyword != "outer" || words.size() != 2 || Lower(words[1]) != "loop") expect("'outer loop'");
        corners.clear();
        state = State::kLoop;
        break;
      case State::kLoop:
        if (keyword == "endloop" && corners.size() >= 3) {
          for (size_t k = 1; k + 1 < corners.size(); ++k) {
            mesh.triangles.push_back({corners[0], corners[k], corners[k + 1]});
          }
          state = State::kEndFacet;
          break;
        }
        if (keyword != "vertex") expect(corners.size() < 3 ? "'vertex x y z'" : "'vertex x y z' or 'endloop'");
        if (words.size() != 4) {
          throw Error(where + "vertex: expected 3 coordinates, got " + std::to_string(words.size() - 1));
        }
        {
          std::array<double, 3> p;
          for (int k = 0; k < 3; ++k) {
            if (!ParseDouble(words[k + 1], &p[k])) {
              throw Error(where + "vertex: '" + std::string(words[k + 1]) + "' is not a number");
            }
            if (!std::isfinite(p[k])) {
              throw Error(where + "vertex: coordinate " + std::string(words[k + 1]) + " is not finite");
            }
          }
          corners.push_back(welder.Add(p));
        }
        break;
      case State::kEndFacet:
        if (keyword != "endfacet") expect("'endfacet'");
        state = State::kInSolid;
        break;
    }
  }
  if (state != State::kBeforeSolid && state != State::kInSolid) {
    throw Error(path + ":" + std::to_string(line_no) + ": the file ends inside a facet");
  }
  if (mesh.triangles.empty()) throw Error(path + ": ASCII STL without facets");
  return mesh;
}

// Binary if the size is 84 + 50·n (n from bytes 80..83), whatever the header
// says (binary headers often start with "solid" too); else ASCII if it starts
// with "solid" and holds no NUL byte (binary triangles almost always do);
// else binary, which then reports the size that is wrong.
bool LooksLikeAsciiStl(std::string_view data) {
  if (data.size() >= 84) {
    const uint64_t count = ReadU32(reinterpret_cast<const unsigned char*>(data.data()) + 80);
    if (data.size() == 84 + 50 * count) return false;
  }
  size_t start = 0;
  while (start < data.size() && std::isspace(static_cast<unsigned char>(data[start]))) ++start;
  if (Lower(data.substr(start, 5)) != "solid") return false;
  return data.find('\0') == std::string_view::npos;
}

}  // namespace

Mesh LoadMesh(const std::string& path) {
  const std::string extension = Lower(std::filesystem::path(path).extension().string());
  if (extension != ".obj" && extension != ".stl") {
    throw Error(path + ": unknown mesh format " + (extension.empty() ? "(no extension)" : "'" + extension + "'") +
                " (expected .obj or .stl)");
  }
  if (std::filesystem::is_directory(path)) throw Error(path + ": is a directory, not a mesh file");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw Error(path + ": cannot open the mesh file (" + std::strerror(errno) + ")");
  std::ostringstream buffer;
  buffer << file.rdbuf();
  if (file.bad()) throw Error(path + ": cannot read the mesh file");
  const std::string data = buffer.str();
  if (extension == ".obj") return ReadObj(path, data);
  return LooksLikeAsciiStl(data) ? ReadAsciiStl(path, data) : ReadBinaryStl(path, data);
}

}  // namespace flowplan::spheres
