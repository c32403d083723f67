// Binary snapshots (output.snapshot_format = "binary", the default): VTK's appended raw data
// compressed by zlib in blocks, read back to the same values and drawn to the same pixels as
// the text snapshots.
#include <gtest/gtest.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <numeric>
#include <string>
#include <vector>

#include "core/error.h"
#include "files.h"
#include "output/frame.h"
#include "output/render_run.h"
#include "run/run.h"
#include "run/vtk_zlib_blocks.h"
#include "scenario/scenario.h"

using namespace demlab;
using demlab::test::read_file;
using demlab::test::temp_dir;
namespace fs = std::filesystem;

TEST(ZlibBlocks, RoundTripAtBlockBoundariesAndRefusesDamage) {
    for (size_t n : {size_t(0), size_t(1), kVtkBlockBytes - 1, kVtkBlockBytes, kVtkBlockBytes + 1, 3 * kVtkBlockBytes + 17}) {
        std::string bytes(n, '\0');
        for (size_t i = 0; i < n; ++i) bytes[i] = char((i * 2654435761u) >> 13);
        std::string appended = "prefix";  // an array after another
        append_zlib_blocks(appended, bytes.data(), bytes.size());
        EXPECT_EQ(read_zlib_blocks(appended, 6, "t.vtp"), bytes) << n;
        // the header: blocks, block size, the last block's size (0: a full one)
        uint64_t h[3];
        std::memcpy(h, appended.data() + 6, sizeof h);
        EXPECT_EQ(h[0], (n + kVtkBlockBytes - 1) / kVtkBlockBytes);
        EXPECT_EQ(h[1], kVtkBlockBytes);
        EXPECT_EQ(h[2], n % kVtkBlockBytes);
        if (n > 100) {
            std::string cut = appended.substr(0, appended.size() - 5);
            EXPECT_THROW(read_zlib_blocks(cut, 6, "t.vtp"), InputError);
            std::string flipped = appended;
            flipped[flipped.size() - 3] = char(flipped[flipped.size() - 3] ^ 0x5a);
            EXPECT_THROW(read_zlib_blocks(flipped, 6, "t.vtp"), InputError);
        }
    }
    EXPECT_THROW(read_zlib_blocks("short", 0, "t.vtp"), InputError);
}

namespace {
fs::path run_in(const std::string& format, const std::string& name) {
    Scenario s = load_scenario(std::string(DEMLAB_SOURCE_DIR) + "/scenarios/geometry-A.toml");
    apply_override(s, "release.scale=20");
    apply_override(s, "stop.t_max=0.25");
    apply_override(s, "output.snapshot_format=\"" + format + "\"");
    finish_scenario(s);
    const fs::path dir = temp_dir(name);
    fs::remove_all(dir);
    run_scenario(s, {dir.string(), false, {}});
    return dir;
}
}  // namespace

TEST(SnapshotFormat, BinaryReadsBackAsTheAsciiValuesAndRendersTheSamePixels) {
    const fs::path bin = run_in("binary", "snap-bin"), text = run_in("ascii", "snap-ascii");
    const std::vector<SnapshotEntry> a = list_snapshots(bin.string()), b = list_snapshots(text.string());
    ASSERT_EQ(a.size(), b.size());
    ASSERT_GE(a.size(), 6u);
    size_t bin_bytes = 0, text_bytes = 0;
    for (size_t k = 0; k < a.size(); ++k) {
        EXPECT_NE(read_file(a[k].discs).find("compressor=\"vtkZLibDataCompressor\""), std::string::npos);
        EXPECT_NE(read_file(b[k].discs).find("format=\"ascii\""), std::string::npos);
        bin_bytes += fs::file_size(a[k].discs);
        text_bytes += fs::file_size(b[k].discs);
        const Frame fa = read_frame(a[k].discs, a[k].walls), fb = read_frame(b[k].discs, b[k].walls);
        EXPECT_EQ(fa.time, fb.time);
        ASSERT_EQ(fa.pos.size(), fb.pos.size());
        ASSERT_EQ(fa.pos.size(), 364u);
        for (size_t i = 0; i < fa.pos.size(); ++i) {
            // the text keeps 12 significant digits of a position, 9 of the rest
            EXPECT_NEAR(fa.pos[i].x(), fb.pos[i].x(), 1e-11);
            EXPECT_NEAR(fa.pos[i].y(), fb.pos[i].y(), 1e-11);
            EXPECT_NEAR(fa.radius[i], fb.radius[i], 1e-11);
            EXPECT_NEAR(fa.angle[i], fb.angle[i], 1e-8 * (1 + std::abs(fb.angle[i])));
            EXPECT_NEAR(fa.speed[i], fb.speed[i], 1e-8 * (1 + fb.speed[i]));
        }
        EXPECT_EQ(fa.layer, fb.layer);
        EXPECT_EQ(fa.grid, fb.grid);
        EXPECT_EQ(fa.wall_id, fb.wall_id);
        ASSERT_EQ(fa.walls.size(), fb.walls.size());
        for (size_t w = 0; w < fa.walls.size(); ++w) ASSERT_EQ(fa.walls[w].size(), fb.walls[w].size());
    }
    // lossless (every double as it is) and still smaller: measured 0.53 of the text
    EXPECT_LT(double(bin_bytes), 0.6 * double(text_bytes));
    // the same pixels, frame by frame
    for (const fs::path& dir : {bin, text}) {
        RenderRunOptions o;
        o.run_dir = dir.string();
        o.out = (dir / "replay").string();
        o.color = "speed";
        EXPECT_EQ(size_t(render_run(o)), a.size());
    }
    for (size_t k = 0; k < a.size(); ++k) {
        char name[32];
        std::snprintf(name, sizeof name, "frame_%05d.png", int(k));
        const std::string pa = read_file(bin / "replay" / name), pb = read_file(text / "replay" / name);
        ASSERT_FALSE(pa.empty());
        EXPECT_EQ(pa, pb) << name;
    }
    // a damaged binary snapshot is an input error, never a crash
    std::string damaged = read_file(a.back().discs);
    damaged.resize(damaged.size() - 200);
    const fs::path bad = bin / "damaged.vtp";
    std::ofstream(bad, std::ios::binary) << damaged;
    EXPECT_THROW(read_frame(bad.string(), a.back().walls), InputError);
    fs::remove_all(bin);
    fs::remove_all(text);
}
