// Off-screen frames: OSMesa (software OpenGL, no display, no GPU) draws the discs as filled
// circles of their true radius, the walls as they are at that instant, the 10 cm marks along
// the flume path and, for the rotation colouring, a radial line per disc; the bonds colouring
// draws the intact bonds as thin lines and the discs by the share of their bonds lost. The scene is drawn
// at `supersample` times the size and box-filtered down: smooth edges without multisampling.
// Text (time, colour bar) comes from FreeType with DejaVu Sans.
#pragma once
#include <memory>
#include <utility>
#include <string>

#include "output/frame.h"
#include "output/image.h"

namespace demlab {

enum class ColorMode { Layers, Grid, Speed, Rotation, Bonds };

struct RenderStyle {
    int width = 1280;            // px
    int height = 720;            // px
    ColorMode color = ColorMode::Layers;
    bool view_set = false;       // false: fit the walls of the frame
    Vec2 view_lo{0, 0}, view_hi{1, 1};  // m, the world window (widened to the image's aspect)
    int supersample = 3;         // drawn at this factor, then averaged down
    double speed_max = 3.0;      // m/s at the top of the speed colour bar
    bool flume_marks = false;    // 10 cm marks along walls 0, 1, 2 (W1, arc, W3)
    bool show_time = true;
};

// Parses "layers", "grid", "speed", "rotation", "bonds"; throws InputError otherwise.
ColorMode parse_color_mode(const std::string& s);

class Renderer {
public:
    explicit Renderer(const RenderStyle& style);
    ~Renderer();
    Renderer(const Renderer&) = delete;
    Renderer& operator=(const Renderer&) = delete;

    Image render(const Frame& f);
    const RenderStyle& style() const { return style_; }

private:
    struct Impl;
    // the window: the view widened to the image's aspect ratio, and its scale
    struct Window {
        Vec2 lo, hi, size;
        double px_per_m;
    };
    Window set_up_view(const Frame& f);
    void draw_discs(const Frame& f, double px_per_m);
    void draw_bonds(const Frame& f, double px_per_m);
    void draw_walls_and_overlays(const Frame& f, double wall_half);
    std::vector<std::pair<Vec2, std::string>> draw_flume_marks(const Frame& f, double wall_half);
    Image read_back_downsampled();
    void annotate(Image& img, const Frame& f, const std::vector<std::pair<Vec2, std::string>>& labels, const Window& win);
    RenderStyle style_;
    std::unique_ptr<Impl> impl_;
};

// The look of `demlab run --frames` and of `demlab render` without options.
RenderStyle default_render_style(bool flume);

// The world window that shows all walls of a frame with a 3 % border.
void fit_view(const Frame& f, Vec2& lo, Vec2& hi);

}  // namespace demlab
