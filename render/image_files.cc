#include "render/image_files.h"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <map>
#include <unordered_map>

#include "core/atomic_file.h"
#include "core/error.h"

namespace flowplan::render {
namespace {

void Put32(std::string& out, uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<char>((v >> shift) & 0xff));
}

void Put16LittleEndian(std::string& out, int v) {
  out.push_back(static_cast<char>(v & 0xff));
  out.push_back(static_cast<char>((v >> 8) & 0xff));
}

void PngChunk(std::string& out, const char* type, const std::string& data) {
  Put32(out, static_cast<uint32_t>(data.size()));
  const std::string body = std::string(type, 4) + data;
  out += body;
  Put32(out, static_cast<uint32_t>(crc32(0L, reinterpret_cast<const Bytef*>(body.data()), static_cast<uInt>(body.size()))));
}

void CheckImage(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0 || image.width > 65535 || image.height > 65535 ||
      image.rgb.size() != 3 * static_cast<size_t>(image.width) * static_cast<size_t>(image.height)) {
    throw Error(path + ": cannot write an image of " + std::to_string(image.width) + " x " +
                std::to_string(image.height) + " pixels from " + std::to_string(image.rgb.size()) + " bytes");
  }
}

/// 15-bit colour key: 5 bits per channel.
int Key(const uint8_t* p) { return ((p[0] >> 3) << 10) | ((p[1] >> 3) << 5) | (p[2] >> 3); }

/// GIF's variable-length LZW codes, packed least significant bit first into 255-byte sub-blocks.
class LzwWriter {
 public:
  explicit LzwWriter(int min_code_size) : min_code_size_(min_code_size) {}

  std::string Encode(const std::vector<uint8_t>& indices) {
    const int clear = 1 << min_code_size_, end = clear + 1;
    Reset();
    Emit(clear);
    if (indices.empty()) {
      Emit(end);
      return Finish();
    }
    int prefix = indices[0];
    for (size_t i = 1; i < indices.size(); ++i) {
      const int c = indices[i];
      const int64_t key = (static_cast<int64_t>(prefix) << 8) | c;
      const auto found = table_.find(key);
      if (found != table_.end()) {
        prefix = found->second;
        continue;
      }
      Emit(prefix);
      if (next_code_ < 4096) {
        table_.emplace(key, next_code_++);
        // The decoder widens its codes one code later than the encoder adds the entry that needs it.
        if (next_code_ > (1 << code_size_) && code_size_ < 12) ++code_size_;
      } else {
        Emit(clear);
        Reset();
      }
      prefix = c;
    }
    Emit(prefix);
    Emit(end);
    return Finish();
  }

 private:
  void Reset() {
    table_.clear();
    code_size_ = min_code_size_ + 1;
    next_code_ = (1 << min_code_size_) + 2;
  }
  void Emit(int code) {
    bits_ |= static_cast<uint64_t>(code) << bit_count_;
    bit_count_ += code_size_;
    while (bit_count_ >= 8) {
      bytes_.push_back(static_cast<char>(bits_ & 0xff));
      bits_ >>= 8;
      bit_count_ -= 8;
    }
  }
  std::string Finish() {
    if (bit_count_ > 0) bytes_.push_back(static_cast<char>(bits_ & 0xff));
    std::string out;
    for (size_t at = 0; at < bytes_.size(); at += 255) {
      const size_t n = std::min<size_t>(255, bytes_.size() - at);
      out.push_back(static_cast<char>(n));
      out.append(bytes_, at, n);
    }
    out.push_back('\0');
    return out;
  }

  int min_code_size_;
  int code_size_ = 0, next_code_ = 0;
  std::unordered_map<int64_t, int> table_;
  uint64_t bits_ = 0;
  int bit_count_ = 0;
  std::string bytes_;
};

}  // namespace

Image Tile(const std::vector<Image>& images, int columns) {
  FLOWPLAN_DEMAND(!images.empty() && columns > 0);
  const int w = images[0].width, h = images[0].height;
  const int n = static_cast<int>(images.size()), cols = std::min(columns, n), rows = (n + cols - 1) / cols;
  Image out;
  out.width = w * cols;
  out.height = h * rows;
  out.rgb.assign(3 * static_cast<size_t>(out.width) * out.height, 255);
  for (int i = 0; i < n; ++i) {
    const Image& image = images[static_cast<size_t>(i)];
    FLOWPLAN_DEMAND(image.width == w && image.height == h && image.rgb.size() == 3 * static_cast<size_t>(w) * h);
    const int x0 = (i % cols) * w, y0 = (i / cols) * h;
    for (int y = 0; y < h; ++y) {
      std::copy_n(image.At(0, y), 3 * static_cast<size_t>(w),
                  &out.rgb[3 * (static_cast<size_t>(y0 + y) * out.width + x0)]);
    }
  }
  return out;
}

void WritePng(const std::string& path, const Image& image) {
  CheckImage(image, path);
  std::string raw;
  raw.reserve(static_cast<size_t>(image.height) * (3 * image.width + 1));
  for (int y = 0; y < image.height; ++y) {
    raw.push_back('\0');  // filter: none
    raw.append(reinterpret_cast<const char*>(image.At(0, y)), 3 * static_cast<size_t>(image.width));
  }
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  std::string compressed(size, '\0');
  if (compress2(reinterpret_cast<Bytef*>(compressed.data()), &size, reinterpret_cast<const Bytef*>(raw.data()),
                static_cast<uLong>(raw.size()), 6) != Z_OK) {
    throw Error(path + ": zlib could not compress the image");
  }
  compressed.resize(size);
  std::string header;
  Put32(header, static_cast<uint32_t>(image.width));
  Put32(header, static_cast<uint32_t>(image.height));
  header += std::string("\x08\x02\x00\x00\x00", 5);  // 8 bits, RGB, deflate, adaptive filters, no interlace
  std::string out = "\x89PNG\r\n\x1a\n";
  PngChunk(out, "IHDR", header);
  PngChunk(out, "IDAT", compressed);
  PngChunk(out, "IEND", "");
  WriteFileAtomically(path, out);
}

void WriteGif(const std::string& path, const std::vector<Image>& frames, double frame_seconds) {
  if (frames.empty()) throw Error(path + ": no frames to write");
  for (const Image& frame : frames) {
    CheckImage(frame, path);
    if (frame.width != frames[0].width || frame.height != frames[0].height) {
      throw Error(path + ": frames of different sizes");
    }
  }
  // The palette: the 256 most common 15-bit colours of all frames (ties by key), each the mean of its pixels.
  std::vector<int64_t> count(1 << 15, 0);
  std::vector<std::array<double, 3>> sum(1 << 15, {0.0, 0.0, 0.0});
  for (const Image& frame : frames) {
    for (size_t i = 0; i < frame.rgb.size(); i += 3) {
      const int k = Key(&frame.rgb[i]);
      ++count[k];
      for (int c = 0; c < 3; ++c) sum[k][c] += frame.rgb[i + c];
    }
  }
  std::vector<int> keys;
  for (int k = 0; k < (1 << 15); ++k) {
    if (count[k] > 0) keys.push_back(k);
  }
  std::stable_sort(keys.begin(), keys.end(), [&](int a, int b) { return count[a] > count[b]; });
  keys.resize(std::min<size_t>(keys.size(), 256));
  std::vector<std::array<int, 3>> palette;
  for (int k : keys) {
    palette.push_back({static_cast<int>(std::lround(sum[k][0] / count[k])), static_cast<int>(std::lround(sum[k][1] / count[k])),
                       static_cast<int>(std::lround(sum[k][2] / count[k]))});
  }
  while (palette.size() < 256) palette.push_back({0, 0, 0});
  // Every 15-bit colour maps to its nearest palette entry (computed once per colour met).
  std::vector<int> nearest(1 << 15, -1);
  auto index_of = [&](const uint8_t* p) {
    const int k = Key(p);
    if (nearest[k] < 0) {
      const int r = ((k >> 10) & 31) * 8 + 4, g = ((k >> 5) & 31) * 8 + 4, b = (k & 31) * 8 + 4;
      int best = 0, best_distance = INT32_MAX;
      for (size_t i = 0; i < keys.size(); ++i) {
        const int dr = palette[i][0] - r, dg = palette[i][1] - g, db = palette[i][2] - b;
        const int d = dr * dr + dg * dg + db * db;
        if (d < best_distance) {
          best_distance = d;
          best = static_cast<int>(i);
        }
      }
      nearest[k] = best;
    }
    return static_cast<uint8_t>(nearest[k]);
  };

  const int width = frames[0].width, height = frames[0].height;
  std::string out = "GIF89a";
  Put16LittleEndian(out, width);
  Put16LittleEndian(out, height);
  out += std::string("\xf7\x00\x00", 3);  // global colour table of 2^(7+1) = 256 entries
  for (const auto& c : palette) {
    for (int v : c) out.push_back(static_cast<char>(v));
  }
  out += std::string("\x21\xff\x0bNETSCAPE2.0\x03\x01\x00\x00\x00", 19);  // loop forever
  const int delay = std::max(1, static_cast<int>(std::lround(frame_seconds * 100.0)));  // 1/100 s
  for (const Image& frame : frames) {
    out += std::string("\x21\xf9\x04\x00", 4);  // graphic control: no disposal, no transparency
    Put16LittleEndian(out, delay);
    out += std::string("\x00\x00", 2);
    out.push_back('\x2c');  // image descriptor: the whole canvas, no local table
    Put16LittleEndian(out, 0);
    Put16LittleEndian(out, 0);
    Put16LittleEndian(out, width);
    Put16LittleEndian(out, height);
    out.push_back('\0');
    std::vector<uint8_t> indices(static_cast<size_t>(width) * height);
    for (size_t i = 0; i < indices.size(); ++i) indices[i] = index_of(&frame.rgb[3 * i]);
    out.push_back('\x08');  // LZW minimum code size
    out += LzwWriter(8).Encode(indices);
  }
  out.push_back('\x3b');
  WriteFileAtomically(path, out);
}

}  // namespace flowplan::render
