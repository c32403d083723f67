#include "output/renderer.h"

#define GL_GLEXT_PROTOTYPES 1  // glMultiDrawArrays (OpenGL 1.4)
#include <GL/gl.h>
#include <GL/osmesa.h>
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstring>
#include <vector>
#include <cstdio>
#include <fstream>
#include <mutex>

#include "core/error.h"
#include "output/colour_map.h"

namespace demlab {

namespace {
const Rgb kBackground{1.0, 1.0, 1.0};
const Rgb kWall{0.16, 0.16, 0.16};
const Rgb kLayerA{0.84, 0.55, 0.24};  // sand
const Rgb kLayerB{0.27, 0.43, 0.67};  // blue bands, as the thesis' layer plots
const Rgb kRotationFill{0.80, 0.80, 0.80};
const Rgb kRotationLine{0.10, 0.10, 0.10};
const Rgb kBondIntact{0.62, 0.74, 0.88};  // a disc with all its bonds: snow blue
const Rgb kBondLine{0.12, 0.20, 0.40};

// A disc by the share q of its bonds that broke: snow blue at 0, orange past 0, dark red at 1;
// a disc that never had a bond is grey.
Rgb bond_colour(int intact, int broken) {
    if (intact + broken == 0) return kRotationFill;
    if (broken == 0) return kBondIntact;
    const double q = double(broken) / double(intact + broken);
    const Rgb lo{0.96, 0.62, 0.20}, hi{0.62, 0.04, 0.04};
    return {lo.r + q * (hi.r - lo.r), lo.g + q * (hi.g - lo.g), lo.b + q * (hi.b - lo.b)};
}

Rgb speed_colour(double v, double vmax) { return viridis(v, vmax); }

const char* kFonts[] = {"/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
                        "/usr/share/fonts/truetype/dejavu/DejaVuSans-Bold.ttf"};
// cos and sin of 2 pi k / segments, k = 0 .. segments, for each segment count a circle uses:
// computed once, not per vertex of every disc of every frame (they were a tenth of drawing
// the discs). The same values the per-vertex calls gave, so the same pixels.
constexpr int kMaxSegments = 72;
struct UnitCircles {
    std::vector<std::pair<double, double>> table[kMaxSegments + 1];
    const std::vector<std::pair<double, double>>& get(int segments) {
        std::vector<std::pair<double, double>>& t = table[segments];
        if (t.empty())
            for (int k = 0; k <= segments; ++k) {
                const double a = 2.0 * kPi * k / segments;
                t.emplace_back(std::cos(a), std::sin(a));
            }
        return t;
    }
};

}  // namespace

ColorMode parse_color_mode(const std::string& s) {
    if (s == "layers") return ColorMode::Layers;
    if (s == "grid") return ColorMode::Grid;
    if (s == "speed") return ColorMode::Speed;
    if (s == "rotation") return ColorMode::Rotation;
    if (s == "bonds") return ColorMode::Bonds;
    throw InputError("--color '" + s + "': must be layers, grid, speed, rotation or bonds");
}

RenderStyle default_render_style(bool flume) {
    RenderStyle s;
    s.flume_marks = flume;
    return s;
}

void fit_view(const Frame& f, Vec2& lo, Vec2& hi) {
    lo = Vec2(INFINITY, INFINITY);
    hi = Vec2(-INFINITY, -INFINITY);
    for (const auto& line : f.walls)
        for (const Vec2& p : line) {
            lo = lo.cwiseMin(p);
            hi = hi.cwiseMax(p);
        }
    if (!std::isfinite(lo.x()))  // no walls: fit the discs
        for (size_t i = 0; i < f.pos.size(); ++i) {
            lo = lo.cwiseMin(f.pos[i] - Vec2(f.radius[i], f.radius[i]));
            hi = hi.cwiseMax(f.pos[i] + Vec2(f.radius[i], f.radius[i]));
        }
    if (!std::isfinite(lo.x())) {
        lo = Vec2(0, 0);
        hi = Vec2(1, 1);
    }
    const Vec2 pad = 0.03 * (hi - lo) + Vec2(1e-3, 1e-3);
    lo -= pad;
    hi += pad;
}

struct Renderer::Impl {
    OSMesaContext ctx = nullptr;
    UnitCircles circles;
    std::vector<double> xy, rgb;          // the discs' fans: vertices (m) and their colours
    std::vector<GLint> first;             // each fan's first vertex
    std::vector<GLsizei> count;           // and its number of vertices
    std::vector<uint8_t> buffer;  // RGBA, bottom row first (OpenGL)
    int w = 0, h = 0;             // supersampled size
    FT_Library ft = nullptr;
    FT_Face face = nullptr;

    void text(Image& img, const std::string& s, int x, int baseline, int px, const Rgb& c) {
        if (!face) return;
        FT_Set_Pixel_Sizes(face, 0, FT_UInt(px));
        for (char ch : s) {
            if (FT_Load_Char(face, FT_ULong(static_cast<unsigned char>(ch)), FT_LOAD_RENDER)) continue;
            const FT_GlyphSlot g = face->glyph;
            for (unsigned row = 0; row < g->bitmap.rows; ++row)
                for (unsigned col = 0; col < g->bitmap.width; ++col) {
                    const int X = x + g->bitmap_left + int(col), Y = baseline - g->bitmap_top + int(row);
                    if (X < 0 || Y < 0 || X >= img.width || Y >= img.height) continue;
                    const double a = g->bitmap.buffer[row * unsigned(g->bitmap.pitch) + col] / 255.0;
                    uint8_t* p = img.at(X, Y);
                    p[0] = uint8_t(std::lround(p[0] * (1 - a) + 255 * c.r * a));
                    p[1] = uint8_t(std::lround(p[1] * (1 - a) + 255 * c.g * a));
                    p[2] = uint8_t(std::lround(p[2] * (1 - a) + 255 * c.b * a));
                }
            x += int(g->advance.x >> 6);
        }
    }
};

Renderer::Renderer(const RenderStyle& style) : style_(style), impl_(std::make_unique<Impl>()) {
    if (style.width < 16 || style.height < 16 || style.width > 8192 || style.height > 8192)
        throw InputError("--size " + std::to_string(style.width) + "x" + std::to_string(style.height) +
                         ": width and height must be in [16, 8192] px");
    if (style.supersample < 1 || style.supersample > 4) throw InputError("supersample must be 1 to 4");
    impl_->w = style.width * style.supersample;
    impl_->h = style.height * style.supersample;
    impl_->ctx = OSMesaCreateContextExt(OSMESA_RGBA, 0, 0, 0, nullptr);
    if (!impl_->ctx) throw RunError("OSMesa could not create an off-screen OpenGL context");
    impl_->buffer.assign(size_t(impl_->w) * size_t(impl_->h) * 4, 0);
    if (!OSMesaMakeCurrent(impl_->ctx, impl_->buffer.data(), GL_UNSIGNED_BYTE, impl_->w, impl_->h))
        throw RunError("OSMesa could not bind the frame buffer");
    if (FT_Init_FreeType(&impl_->ft) == 0)
        for (const char* path : kFonts)
            if (FT_New_Face(impl_->ft, path, 0, &impl_->face) == 0) break;
    if (!impl_->face) {
        static std::once_flag warned;  // once per process, however many renderers (render_run's threads)
        std::call_once(warned, [] {
            std::fprintf(stderr, "demlab: warning: no DejaVu font found (install fonts-dejavu-core); frames carry no text\n");
        });
    }
}

Renderer::~Renderer() {
    if (impl_->face) FT_Done_Face(impl_->face);
    if (impl_->ft) FT_Done_FreeType(impl_->ft);
    if (impl_->ctx) OSMesaDestroyContext(impl_->ctx);
}

namespace {
void colour(const Rgb& c) { glColor3d(c.r, c.g, c.b); }

void thick_segment(const Vec2& a, const Vec2& b, double half_width) {
    const Vec2 d = b - a;
    const double len = d.norm();
    if (len == 0) return;
    const Vec2 n = perp(d / len) * half_width;
    glBegin(GL_QUADS);
    glVertex2d(a.x() + n.x(), a.y() + n.y());
    glVertex2d(b.x() + n.x(), b.y() + n.y());
    glVertex2d(b.x() - n.x(), b.y() - n.y());
    glVertex2d(a.x() - n.x(), a.y() - n.y());
    glEnd();
}

void filled_circle(UnitCircles& unit, const Vec2& c, double r, int segments) {
    glBegin(GL_TRIANGLE_FAN);
    glVertex2d(c.x(), c.y());
    for (const auto& [cos_a, sin_a] : unit.get(segments)) glVertex2d(c.x() + r * cos_a, c.y() + r * sin_a);
    glEnd();
}
}  // namespace

Renderer::Window Renderer::set_up_view(const Frame& f) {
    Impl& im = *impl_;
    if (!OSMesaMakeCurrent(im.ctx, im.buffer.data(), GL_UNSIGNED_BYTE, im.w, im.h))
        throw RunError("OSMesa could not bind the frame buffer");
    Vec2 lo = style_.view_lo, hi = style_.view_hi;
    if (!style_.view_set) fit_view(f, lo, hi);
    // widen the window to the image's aspect ratio, so discs stay round
    const double aspect = double(style_.width) / style_.height;
    Vec2 size = hi - lo, mid = 0.5 * (hi + lo);
    if (size.x() / size.y() < aspect) size.x() = size.y() * aspect;
    else size.y() = size.x() / aspect;
    lo = mid - 0.5 * size;
    hi = mid + 0.5 * size;
    const double px_per_m = im.w / size.x();

    glViewport(0, 0, im.w, im.h);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    glOrtho(lo.x(), hi.x(), lo.y(), hi.y(), -1, 1);
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();
    glDisable(GL_DEPTH_TEST);
    glClearColor(float(kBackground.r), float(kBackground.g), float(kBackground.b), 1.0f);
    glClear(GL_COLOR_BUFFER_BIT);

    return {lo, hi, size, px_per_m};
}

void Renderer::draw_discs(const Frame& f, double px_per_m) {
    Impl& im = *impl_;
    for (const Frame::Fill& fill : f.fills) {
        glColor3d(fill.r, fill.g, fill.b);
        glBegin(GL_POLYGON);
        for (const Vec2& p : fill.polygon) glVertex2d(p.x(), p.y());
        glEnd();
    }
    // discs: the same fans as glBegin(GL_TRIANGLE_FAN) per disc, from arrays in one call (the
    // immediate mode's call per vertex was most of OSMesa's time for a flume's 9,101 discs)
    im.xy.clear();
    im.rgb.clear();
    im.first.clear();
    im.count.clear();
    for (size_t i = 0; i < f.pos.size(); ++i) {
        Rgb c = kRotationFill;
        switch (style_.color) {
            case ColorMode::Layers: c = (f.layer[i] % 2 == 0) ? kLayerA : kLayerB; break;
            case ColorMode::Grid: c = ((f.grid[i] % 1000 + f.grid[i] / 1000) % 2 == 0) ? kLayerA : kLayerB; break;
            case ColorMode::Speed: c = speed_colour(f.speed[i], style_.speed_max); break;
            case ColorMode::Rotation: c = kRotationFill; break;
            case ColorMode::Bonds:
                c = f.bonds_intact.empty() ? kRotationFill : bond_colour(f.bonds_intact[i], f.bonds_broken[i]);
                break;
        }
        // 12 to kMaxSegments, decided on the double before any cast: a huge radius gives the
        // most and a NaN one the fewest, never an int overflow (undefined behaviour)
        const double want = f.radius[i] * px_per_m * 1.5;
        const int segments = want >= kMaxSegments ? kMaxSegments : want > 12.0 ? int(want) : 12;
        im.first.push_back(GLint(im.xy.size() / 2));
        const Vec2 p = f.pos[i];
        const double r = f.radius[i];
        im.xy.insert(im.xy.end(), {p.x(), p.y()});
        for (const auto& [cos_a, sin_a] : im.circles.get(segments)) im.xy.insert(im.xy.end(), {p.x() + r * cos_a, p.y() + r * sin_a});
        im.count.push_back(GLsizei(segments + 2));
        for (int k = 0; k < segments + 2; ++k) im.rgb.insert(im.rgb.end(), {c.r, c.g, c.b});
    }
    if (!im.first.empty()) {
        glEnableClientState(GL_VERTEX_ARRAY);
        glEnableClientState(GL_COLOR_ARRAY);
        glVertexPointer(2, GL_DOUBLE, 0, im.xy.data());
        glColorPointer(3, GL_DOUBLE, 0, im.rgb.data());
        glMultiDrawArrays(GL_TRIANGLE_FAN, im.first.data(), im.count.data(), GLsizei(im.first.size()));
        glDisableClientState(GL_COLOR_ARRAY);
        glDisableClientState(GL_VERTEX_ARRAY);
    }
    if (style_.color == ColorMode::Rotation) {
        colour(kRotationLine);
        for (size_t i = 0; i < f.pos.size(); ++i) {
            const Vec2 tip = f.pos[i] + f.radius[i] * Vec2(std::cos(f.angle[i]), std::sin(f.angle[i]));
            thick_segment(f.pos[i], tip, std::max(0.75 * style_.supersample / px_per_m, 0.08 * f.radius[i]));
        }
    }
}

// the intact bonds, centre to centre, 1 px wide (at least a tenth of the thinnest bond's
// discs, so a zoomed view keeps them in proportion)
void Renderer::draw_bonds(const Frame& f, double px_per_m) {
    if (style_.color != ColorMode::Bonds || f.bonds.empty()) return;
    colour(kBondLine);
    const double half_px = 0.5 * style_.supersample / px_per_m;
    for (const auto& [k, l] : f.bonds) {
        const double r = std::min(f.radius[size_t(k)], f.radius[size_t(l)]);
        thick_segment(f.pos[size_t(k)], f.pos[size_t(l)], std::max(half_px, 0.05 * r));
    }
}

void Renderer::draw_walls_and_overlays(const Frame& f, double wall_half) {
    Impl& im = *impl_;
    // walls, 3 px wide, with round joints
    colour(kWall);
    for (const auto& line : f.walls) {
        for (size_t k = 0; k + 1 < line.size(); ++k) thick_segment(line[k], line[k + 1], wall_half);
        for (const Vec2& p : line) filled_circle(im.circles, p, wall_half, 12);
    }
    // analysis overlays, 2 px wide
    for (const auto& ov : f.overlays) {
        glColor3d(ov.r, ov.g, ov.b);
        for (size_t k = 0; k + 1 < ov.line.size(); ++k) thick_segment(ov.line[k], ov.line[k + 1], 0.66 * wall_half);
    }
}

// 10 cm marks along W1, arc, W3 (walls 0, 1, 2), on the solid side; longer every 0.5 m. Returns
// the labels to write once the image is read back.
std::vector<std::pair<Vec2, std::string>> Renderer::draw_flume_marks(const Frame& f, double wall_half) {
    std::vector<std::pair<Vec2, std::string>> labels;
    {
        std::vector<Vec2> path;
        for (int id = 0; id < 3; ++id)
            for (size_t k = 0; k < f.wall_id.size(); ++k)
                if (f.wall_id[k] == id)
                    for (const Vec2& p : f.walls[k])
                        if (path.empty() || (path.back() - p).norm() > 1e-9) path.push_back(p);
        double s = 0.0, next = 0.0;
        for (size_t k = 0; k + 1 < path.size(); ++k) {
            const Vec2 d = path[k + 1] - path[k];
            const double len = d.norm();
            if (len == 0) continue;
            const Vec2 solid = -perp(d / len);
            while (next <= s + len + 1e-9) {
                const Vec2 p = path[k] + (next - s) / len * d;
                const int tenth = int(std::lround(next * 10.0));
                const double tick = (tenth % 5 == 0) ? 0.03 : 0.015;
                thick_segment(p, p + tick * solid, 0.6 * wall_half);
                if (tenth % 5 == 0 && tenth > 0) {
                    char buf[16];
                    std::snprintf(buf, sizeof buf, "s = %.1f", next);  // distance along the bed, not x
                    labels.emplace_back(p + 0.05 * solid, buf);
                }
                next += 0.1;
            }
            s += len;
        }
    }
    return labels;
}

Image Renderer::read_back_downsampled() {
    Impl& im = *impl_;
    return box_filter_down(im.buffer.data(), im.w, im.h, style_.supersample);
}

// The labels, notes, time and speed bar, in pixels.
void Renderer::annotate(Image& img, const Frame& f, const std::vector<std::pair<Vec2, std::string>>& labels,
                        const Window& win) {
    Impl& im = *impl_;
    const Vec2 lo = win.lo, hi = win.hi, size = win.size;
    const int font_px = std::max(10, style_.height / 28);
    const auto to_pixel = [&](const Vec2& p) {
        return std::pair<int, int>(int((p.x() - lo.x()) / size.x() * img.width),
                                   int((hi.y() - p.y()) / size.y() * img.height));
    };
    for (const auto& [p, s] : labels) {
        const auto [x, y] = to_pixel(p);
        im.text(img, s + " m", x - font_px, y + font_px / 2, std::max(8, font_px * 2 / 3), kWall);
    }
    for (const auto& [p, text] : f.notes) {
        const auto [x, y] = to_pixel(p);
        im.text(img, text, x, y, std::max(9, font_px * 3 / 4), {0.6, 0.05, 0.05});
    }
    if (style_.show_time) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "t = %.2f s", f.time);
        im.text(img, buf, font_px / 2, font_px + font_px / 2, font_px, {0, 0, 0});
    }
    // what the colours mean, top right (the speed mode has its bar below)
    {
        const int sw = std::max(6, font_px * 2 / 3), text_px = std::max(8, font_px * 2 / 3);
        const auto swatch = [&](int x0, int y0, const Rgb& c) {
            for (int y = y0; y < std::min(img.height, y0 + sw); ++y)
                for (int x = x0; x < std::min(img.width, x0 + sw); ++x) {
                    uint8_t* q = img.at(x, y);
                    q[0] = uint8_t(std::lround(255 * c.r));
                    q[1] = uint8_t(std::lround(255 * c.g));
                    q[2] = uint8_t(std::lround(255 * c.b));
                }
        };
        struct Entry {
            Rgb colour;
            const char* text;
        };
        std::vector<Entry> key;
        switch (style_.color) {
            case ColorMode::Layers: key = {{kLayerA, "release layers 1, 3, 5, ... (from the bottom)"}, {kLayerB, "layers 2, 4, 6, ..."}}; break;
            case ColorMode::Grid: key = {{kLayerA, "release cells, alternating"}, {kLayerB, "their neighbours"}}; break;
            case ColorMode::Bonds: key = {{kBondIntact, "all bonds intact (orange to red: share lost)"}, {kBondLine, "intact bond"}}; break;
            case ColorMode::Rotation: key = {{kRotationLine, "a line per disc: its rotation"}}; break;
            case ColorMode::Speed: break;
        }
        size_t longest = 0;  // (about 0.6 of the font size a character, DejaVu Sans)
        for (const Entry& e : key) longest = std::max(longest, std::strlen(e.text));
        const int x0 = img.width - sw - text_px - int(0.62 * double(text_px) * double(longest));
        for (size_t k = 0; k < key.size() && x0 > 0; ++k) {
            const int y = font_px / 2 + int(k) * (sw + text_px / 2);
            swatch(x0, y, key[k].colour);
            im.text(img, key[k].text, x0 + sw + text_px / 2, y + sw, text_px, {0, 0, 0});
        }
    }
    if (style_.color == ColorMode::Speed) {
        // colour bar on the right: 0 at the bottom, speed_max at the top
        const int bar_w = std::max(8, img.width / 80), bar_h = img.height / 2;
        const int x0 = img.width - bar_w - 5 * font_px / 2, y0 = img.height / 4;
        for (int y = 0; y < bar_h; ++y) {
            const Rgb c = speed_colour(double(bar_h - 1 - y) / (bar_h - 1) * style_.speed_max, style_.speed_max);
            for (int x = 0; x < bar_w; ++x) {
                uint8_t* q = img.at(x0 + x, y0 + y);
                q[0] = uint8_t(std::lround(255 * c.r));
                q[1] = uint8_t(std::lround(255 * c.g));
                q[2] = uint8_t(std::lround(255 * c.b));
            }
        }
        char top[32];
        std::snprintf(top, sizeof top, "%.1f m/s", style_.speed_max);
        im.text(img, top, x0 - font_px / 2, y0 - font_px / 3, font_px * 2 / 3, {0, 0, 0});
        im.text(img, "0", x0 + bar_w / 4, y0 + bar_h + font_px, font_px * 2 / 3, {0, 0, 0});
    }
}

Image Renderer::render(const Frame& f) {
    const Window win = set_up_view(f);
    draw_discs(f, win.px_per_m);
    draw_bonds(f, win.px_per_m);
    const double wall_half = 1.5 * style_.supersample / win.px_per_m;
    draw_walls_and_overlays(f, wall_half);
    const auto labels = style_.flume_marks ? draw_flume_marks(f, wall_half) : std::vector<std::pair<Vec2, std::string>>{};
    glFinish();
    Image img = read_back_downsampled();
    annotate(img, f, labels, win);
    return img;
}

}  // namespace demlab
