// An RGB image (rows top to bottom) and PNG files through libpng.
#pragma once
#include <cstdint>
#include <string>
#include <vector>

namespace demlab {

struct Image {
    int width = 0, height = 0;
    std::vector<uint8_t> rgb;  // 3 bytes a pixel, row 0 at the top
    uint8_t* at(int x, int y) { return &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
    const uint8_t* at(int x, int y) const { return &rgb[(size_t(y) * size_t(width) + size_t(x)) * 3]; }
};

void write_png(const std::string& path, const Image& img);  // atomic: temporary file, then rename
Image read_png(const std::string& path);

}  // namespace demlab

namespace demlab {

// An RGBA frame buffer of w x h pixels, bottom row first (OpenGL's), box-filtered down by ss
// in each direction to an Image of (w / ss) x (h / ss), top row first.
Image box_filter_down(const uint8_t* rgba, int w, int h, int ss);

}  // namespace demlab
