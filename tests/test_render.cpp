// Frames: pixel colours of a known scene, disc size in pixels, no display needed, replay equal
// to rendering during the run; plots from a run's CSVs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <cstring>
#include <unistd.h>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "core/error.h"
#include "files.h"
#include "output/frame.h"
#include "output/image.h"
#include "output/plot.h"
#include "output/render_run.h"
#include "output/renderer.h"
#include "run/run.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::read_file;
namespace fs = std::filesystem;

namespace {
// a disc of radius 0.1 m at (0.5, 0.5) in layer 0, a second in layer 1, a horizontal wall at y = 0.2
Frame known_scene() {
    Frame f;
    f.time = 1.25;
    f.pos = {Vec2(0.5, 0.5), Vec2(0.8, 0.8)};
    f.radius = {0.1, 0.05};
    f.angle = {0.0, 0.0};
    f.speed = {0.0, 0.0};
    f.layer = {0, 1};
    f.grid = {0, 0};
    f.walls = {{Vec2(0.0, 0.2), Vec2(1.0, 0.2)}};
    f.wall_id = {0};
    return f;
}

RenderStyle unit_view(int px) {
    RenderStyle s;
    s.width = px;
    s.height = px;
    s.view_set = true;
    s.view_lo = Vec2(0, 0);
    s.view_hi = Vec2(1, 1);
    s.show_time = false;
    return s;
}

int colour_distance(const uint8_t* p, int r, int g, int b) { return std::abs(p[0] - r) + std::abs(p[1] - g) + std::abs(p[2] - b); }
// A snapshot pair in the writer's layout, with the discs' arrays given as text.
void write_vtp_pair(const fs::path& dir, const std::string& points, const std::string& radius, const std::string& layer) {
    fs::create_directories(dir);
    std::ofstream d(dir / "discs.vtp");
    d << "<?xml version=\"1.0\"?>\n<VTKFile type=\"PolyData\">\n<PolyData>\n<FieldData>\n"
         "<DataArray type=\"Float64\" Name=\"TIME\" NumberOfTuples=\"1\" format=\"ascii\">0.125</DataArray>\n</FieldData>\n"
         "<Piece><Points>\n<DataArray type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\" format=\"ascii\">\n"
      << points << "\n</DataArray>\n</Points>\n"
      << "<DataArray type=\"Float64\" Name=\"radius\" format=\"ascii\">\n" << radius << "\n</DataArray>\n"
      << "<DataArray type=\"Float64\" Name=\"angle\" format=\"ascii\">\n0 1.5\n</DataArray>\n"
      << "<DataArray type=\"Float64\" Name=\"speed\" format=\"ascii\">\n2 0\n</DataArray>\n"
      << "<DataArray type=\"Int32\" Name=\"layer\" format=\"ascii\">\n" << layer << "\n</DataArray>\n"
      << "<DataArray type=\"Int32\" Name=\"grid\" format=\"ascii\">\n7 -3\n</DataArray>\n</Piece>\n</PolyData>\n</VTKFile>\n";
    std::ofstream w(dir / "walls.vtp");
    w << "<VTKFile><PolyData><Piece><Points>\n<DataArray type=\"Float64\" Name=\"Points\" format=\"ascii\">\n"
         "0 0 0 1 0.5 0 2 0 0\n</DataArray>\n</Points>\n<CellData><DataArray type=\"Int32\" Name=\"wall\" format=\"ascii\">4</DataArray>"
         "</CellData><Lines><DataArray type=\"Int64\" Name=\"offsets\" format=\"ascii\">3</DataArray></Lines></Piece></PolyData></VTKFile>\n";
}
}  // namespace

// The frame reader parses with std::from_chars: every value must be the double
// strtod gives for its text, bit for bit, whatever the number of digits or the exponent.
TEST(Frame, ReadsTheSnapshotsNumbersExactlyAsStrtod) {
    const fs::path dir = fs::temp_directory_path() / ("demlab-frame-" + std::to_string(::getpid()));
    const char* xs[] = {"0.1", "-2.5e-3", "1.23456789012", "-0", "4.9406564584124654e-324", "1e+300", "0.30000000000000004", "7"};
    std::string points, radius;
    for (int k = 0; k < 2; ++k) points += std::string(xs[4 * k]) + " " + xs[4 * k + 1] + " 0\n";
    radius = std::string(xs[2]) + "\t" + xs[3] + "\r\n";
    write_vtp_pair(dir, points, radius, "0 1");
    const Frame f = read_frame((dir / "discs.vtp").string(), (dir / "walls.vtp").string());
    ASSERT_EQ(f.pos.size(), 2u);
    const auto same_bits = [](double a, const char* text) {
        const double b = std::strtod(text, nullptr);
        return std::memcmp(&a, &b, sizeof a) == 0;
    };
    EXPECT_TRUE(same_bits(f.pos[0].x(), xs[0]));
    EXPECT_TRUE(same_bits(f.pos[0].y(), xs[1]));
    EXPECT_TRUE(same_bits(f.pos[1].x(), xs[4]));
    EXPECT_TRUE(same_bits(f.pos[1].y(), xs[5]));
    EXPECT_TRUE(same_bits(f.radius[0], xs[2]));
    EXPECT_TRUE(same_bits(f.radius[1], xs[3]));  // -0 keeps its sign
    EXPECT_EQ(f.time, 0.125);
    EXPECT_EQ(f.grid, (std::vector<int>{7, -3}));
    EXPECT_EQ(f.angle[1], 1.5);
    ASSERT_EQ(f.walls.size(), 1u);
    ASSERT_EQ(f.walls[0].size(), 3u);
    EXPECT_EQ(f.walls[0][1], Vec2(1, 0.5));
    EXPECT_EQ(f.wall_id, (std::vector<int>{4}));

    // a value that is not a number ends its array, which then has the wrong length: an error
    // that names the file, not a frame drawn from half the discs
    write_vtp_pair(dir, points, std::string(xs[2]) + " oops", "0 1");
    try {
        read_frame((dir / "discs.vtp").string(), (dir / "walls.vtp").string());
        ADD_FAILURE() << "a malformed radius array was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("discs.vtp: arrays of different lengths"), std::string::npos) << e.what();
    }
    // nor is a state that is not finite drawn
    write_vtp_pair(dir, points, std::string(xs[2]) + " nan", "0 1");
    EXPECT_THROW(read_frame((dir / "discs.vtp").string(), (dir / "walls.vtp").string()), InputError);
    write_vtp_pair(dir, std::string("inf 0 0\n") + points.substr(points.find('\n') + 1), radius, "0 1");
    EXPECT_THROW(read_frame((dir / "discs.vtp").string(), (dir / "walls.vtp").string()), InputError);
    // a truncated file: the array never closes
    {
        const std::string text = read_file(dir / "discs.vtp");
        std::ofstream((dir / "discs.vtp")) << text.substr(0, text.find("</DataArray>\n</Points>"));
    }
    EXPECT_THROW(read_frame((dir / "discs.vtp").string(), (dir / "walls.vtp").string()), InputError);
    fs::remove_all(dir);
}

TEST(Renderer, KnownSceneHasTheRightColoursWhereExpected) {
    Renderer r(unit_view(400));  // 400 px per metre
    const Image img = r.render(known_scene());
    ASSERT_EQ(img.width, 400);
    ASSERT_EQ(img.height, 400);
    // inside the first disc: the sand colour of even layers (0.84, 0.55, 0.24)
    EXPECT_LE(colour_distance(img.at(200, 200), 214, 140, 61), 3);
    // inside the second disc (layer 1): the blue band (0.27, 0.43, 0.67); y = 0.8 m is row 80
    EXPECT_LE(colour_distance(img.at(320, 80), 69, 110, 171), 3);
    // outside: the white background
    EXPECT_EQ(colour_distance(img.at(50, 50), 255, 255, 255), 0);
    // on the wall (y = 0.2 m: row 320): the wall's dark grey
    EXPECT_LE(colour_distance(img.at(100, 320), 41, 41, 41), 3);
}

TEST(Renderer, DiscOfRadiusRSpansTwoRPixels) {
    Renderer r(unit_view(400));
    const Image img = r.render(known_scene());
    // across the row through the first disc's centre, count pixels darker than half way
    double covered = 0;
    for (int x = 0; x < 400; ++x) {
        const uint8_t* p = img.at(x, 200);
        if (x > 300) break;
        covered += (255.0 - p[2]) / (255.0 - 61.0);  // blue channel: 255 background, 61 disc (partial at edges)
    }
    EXPECT_NEAR(covered, 2 * 0.1 * 400, 1.0);  // 80 px within one pixel
}

// A disc of any radius, however absurd (a hand-edited snapshot, a frame built by a program),
// is drawn without an int overflow in its segment count; the sane discs as before. (The
// sanitizer pass checks float-to-int casts: the count was once int(radius * px) first.)
TEST(Renderer, AbsurdRadiiAreDrawnWithoutOverflow) {
    Frame f = known_scene();
    f.pos.push_back(Vec2(0.2, 0.8));
    f.radius.push_back(1e300);
    f.pos.push_back(Vec2(0.8, 0.3));
    f.radius.push_back(std::nan(""));
    for (std::vector<double>* v : {&f.angle, &f.speed}) v->resize(f.pos.size(), 0.0);
    f.layer.resize(f.pos.size(), 0);
    f.grid.resize(f.pos.size(), 0);
    Renderer r(unit_view(100));
    const Image img = r.render(f);
    EXPECT_EQ(img.width, 100);
    EXPECT_EQ(img.height, 100);
}

TEST(Renderer, WorksWithoutADisplay) {
    const char* display = std::getenv("DISPLAY");
    const std::string saved = display ? display : "";
    unsetenv("DISPLAY");
    {
        Renderer r(unit_view(64));
        const Image img = r.render(known_scene());
        EXPECT_EQ(img.width, 64);
    }
    if (display) setenv("DISPLAY", saved.c_str(), 1);
}

// The bonds colouring: an intact bond as a line between the centres, a disc with all its
// bonds in snow blue, one that lost half of them half way from orange to dark red, one that
// never had a bond grey; the other colourings draw no bonds.
TEST(Renderer, BondsColouringDrawsBondsAndMarksDiscsThatLostThem) {
    Frame f;
    f.pos = {Vec2(0.2, 0.5), Vec2(0.8, 0.5), Vec2(0.5, 0.8)};
    f.radius = {0.05, 0.05, 0.05};
    f.angle = f.speed = {0.0, 0.0, 0.0};
    f.layer = f.grid = {0, 0, 0};
    f.bonds_intact = {1, 1, 0};
    f.bonds_broken = {0, 1, 0};
    f.bonds = {{0, 1}};
    RenderStyle style = unit_view(400);
    style.color = parse_color_mode("bonds");
    const Image img = Renderer(style).render(f);
    EXPECT_LE(colour_distance(img.at(70, 190), 158, 189, 224), 3);   // disc 0, beside the line
    EXPECT_LE(colour_distance(img.at(330, 190), 201, 84, 31), 3);    // disc 1: (0.79, 0.33, 0.12)
    EXPECT_LE(colour_distance(img.at(200, 60), 204, 204, 204), 3);   // disc 2: no bonds
    EXPECT_LE(colour_distance(img.at(200, 199), 31, 51, 102), 12);   // the bond, between the discs
    EXPECT_EQ(colour_distance(img.at(200, 190), 255, 255, 255), 0);  // and only there
    style.color = ColorMode::Layers;
    EXPECT_EQ(colour_distance(Renderer(style).render(f).at(200, 199), 255, 255, 255), 0);
}

TEST(Renderer, RefusesBadOptions) {
    RenderStyle s;
    s.width = 0;
    EXPECT_THROW(Renderer{s}, InputError);
    EXPECT_THROW(parse_color_mode("rainbow"), InputError);
}

class SmallRun : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir_ = new fs::path(fs::temp_directory_path() / ("demlab-render-" + std::to_string(::getpid())));
        fs::remove_all(*dir_);
        const std::string text = R"(
[scenario]
name = "drop"
[stop]
t_max = 0.12
rest_duration = 0.05
[output]
series_interval = 0.005
snapshot_interval = 0.02
[[walls]]
type = "segment"
start = [-0.2, 0.0]
end = [0.3, -0.05]
[[walls]]
type = "arc"
centre = [0.0, 0.1]
radius = 0.1
start_deg = 180
end_deg = 270
[[discs]]
position = [0.0, 0.05]
radius = 0.01
velocity = [0.4, 0.0]
omega = 5.0
[[discs]]
position = [0.05, 0.05]
radius = 0.015
)";
        Scenario s = parse_scenario(text, "drop.toml");
        finish_scenario(s);
        RunOptions ro{dir_->string(), false, {}};
        attach_frame_hook(ro, false);
        run_scenario(s, ro);
    }
    static void TearDownTestSuite() {
        fs::remove_all(*dir_);
        delete dir_;
    }
    static fs::path* dir_;
};
fs::path* SmallRun::dir_ = nullptr;

TEST_F(SmallRun, ReplayEqualsTheFramesRenderedDuringTheRun) {
    RenderRunOptions o;
    o.run_dir = dir_->string();
    o.out = (*dir_ / "replay").string();
    const int n = render_run(o);
    EXPECT_EQ(size_t(n), list_snapshots(dir_->string()).size());  // t = 0, 0.02, ..., 0.12 and the end
    EXPECT_GE(n, 7);
    for (int k = 0; k < n; ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.png", k);
        const std::string during = read_file(*dir_ / "frames" / name), replay = read_file(*dir_ / "replay" / name);
        ASSERT_FALSE(during.empty()) << name;
        EXPECT_EQ(during, replay) << name;
    }
}

// Replay renders frames on several threads, each with its own renderer: the files must be the
// same bytes for any count (and the strip, tiled in frame order).
TEST_F(SmallRun, ReplayIsTheSameBytesForAnyThreadCount) {
    std::vector<std::string> outs;
    for (int threads : {1, 3}) {
        RenderRunOptions o;
        o.run_dir = dir_->string();
        o.threads = threads;
        o.color = "speed";
        o.out = (*dir_ / ("threads" + std::to_string(threads))).string();
        o.strip = o.out + "-strip.png";
        EXPECT_GE(render_run(o), 7);
        outs.push_back(o.out);
    }
    size_t compared = 0;
    for (const auto& entry : fs::directory_iterator(outs[0])) {
        const std::string name = entry.path().filename().string();
        EXPECT_EQ(read_file(entry.path()), read_file(fs::path(outs[1]) / name)) << name;
        ++compared;
    }
    EXPECT_GE(compared, 7u);
    EXPECT_EQ(read_file(outs[0] + "-strip.png"), read_file(outs[1] + "-strip.png"));
    // and a bad count is refused with the option's name
    RenderRunOptions bad;
    bad.run_dir = dir_->string();
    bad.out = (*dir_ / "bad").string();
    bad.threads = -1;
    try {
        render_run(bad);
        ADD_FAILURE() << "--threads -1 was accepted";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("--threads"), std::string::npos) << e.what();
    }
}

TEST_F(SmallRun, FramesEveryStepOfSnapshotsOnlyAndNeverInterpolated) {
    RenderRunOptions o;
    o.run_dir = dir_->string();
    o.out = (*dir_ / "every4").string();
    o.every = 0.04;
    o.size = "320x200";
    o.color = "rotation";
    EXPECT_EQ(render_run(o), 4);  // 0, 0.04, 0.08, 0.12
    EXPECT_EQ(read_png((*dir_ / "every4" / "frame_00000.png").string()).width, 320);
    o.out = (*dir_ / "every-too-fine").string();
    o.every = 0.01;  // snapshots are 0.02 apart
    EXPECT_THROW(render_run(o), InputError);
    o.out = (*dir_ / "every4").string();  // exists: refused without --force
    o.every = 0.04;
    EXPECT_THROW(render_run(o), InputError);
}

TEST_F(SmallRun, PlotsAreValidPngsOfTheRequestedSize) {
    if (!gnuplot_available()) GTEST_SKIP() << "gnuplot is not installed";
    const auto made = make_plots(dir_->string(), 640, 400);
    ASSERT_FALSE(made.empty());
    for (const auto& p : made) {
        const Image img = read_png(p);
        EXPECT_EQ(img.width, 640) << p;
        EXPECT_EQ(img.height, 400) << p;
    }
}

// A run without bonds has none to colour by
TEST_F(SmallRun, BondsColouringIsRefusedWithoutBonds) {
    RenderRunOptions o;
    o.run_dir = dir_->string();
    o.out = (*dir_ / "bonds").string();
    o.color = "bonds";
    try {
        render_run(o);
        FAIL() << "rendered bonds of a run without bonds";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("hold no bonds"), std::string::npos) << e.what();
    }
    EXPECT_FALSE(fs::exists(*dir_ / "bonds"));  // refused before any output
}
