#pragma once

// Image and video files from RGB frames: PNG (zlib) and animated GIF (a
// palette of the frames' 256 most common colours, LZW by hand). No other
// dependency, so that a fresh machine writes them with Debian's zlib alone.

#include <cstdint>
#include <string>
#include <vector>

namespace flowplan::render {

/// An RGB image, rows top to bottom, 3 bytes per pixel.
struct Image {
  int width = 0, height = 0;
  std::vector<uint8_t> rgb;  // (height, width, 3)

  const uint8_t* At(int x, int y) const { return &rgb[3 * (static_cast<size_t>(y) * width + x)]; }
};

/// `images` (all of one size, at least one) side by side, `columns` to a row, left to right then top to bottom;
/// a last row that is not full is filled with white. @throws flowplan::InternalError for sizes that differ.
Image Tile(const std::vector<Image>& images, int columns);

/// Writes `image` as a PNG file, atomically. @throws flowplan::Error naming the file.
void WritePng(const std::string& path, const Image& image);

/// Writes `frames` (all of one size) as an animated GIF that loops, each frame
/// shown `frame_seconds`, atomically. Colours are reduced to one palette of
/// 256 for the whole animation. @throws flowplan::Error naming the file.
void WriteGif(const std::string& path, const std::vector<Image>& frames, double frame_seconds);

}  // namespace flowplan::render
