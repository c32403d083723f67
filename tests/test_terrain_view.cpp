// Pictures of a 3-D run (src/output/terrain_view.h): a sphere on a terrain seen from above and
// obliquely, one buried in it hidden by the depth test, and a field over the hillshade.
#include <gtest/gtest.h>

#include "output/terrain_view.h"

using namespace demlab;

namespace {
// a flat square of 2 x 2 cells of 10 m, z = 0, as triangles
struct Flat {
    std::vector<Vec3> v;
    std::vector<std::array<std::uint32_t, 3>> t;
    Flat() {
        for (int r = 0; r <= 2; ++r)
            for (int c = 0; c <= 2; ++c) v.emplace_back(10.0 * c, 10.0 * r, 0.0);
        for (std::uint32_t r = 0; r < 2; ++r)
            for (std::uint32_t c = 0; c < 2; ++c) {
                const std::uint32_t a = r * 3 + c;
                t.push_back({a, a + 1, a + 4});
                t.push_back({a, a + 4, a + 3});
            }
    }
};

bool greyish_or_terrain(const uint8_t* p) { return p[0] >= p[2]; }  // the terrain's tints are warm or neutral
}  // namespace

TEST(TerrainView, ASphereOnTheTerrainIsSeenAndABuriedOneIsNot) {
    Flat f;
    TerrainScene scene;
    scene.vertices = &f.v;
    scene.triangles = &f.t;
    scene.centres = {Vec3(10, 10, 2.0), Vec3(15, 5, -3.0)};  // on it, and buried below it
    scene.radius = {2.0, 2.0};
    scene.speed = {0.0, 0.0};  // viridis' bottom: dark violet, blue above red
    TerrainViewDef d;
    d.camera = TerrainCamera::Map;
    d.width = 200;
    d.height = 200;
    const Image img = render_terrain(scene, d);
    ASSERT_EQ(img.width, 200);
    const uint8_t* centre = img.at(100, 100);
    EXPECT_LT(centre[0], centre[2]) << "the sphere (violet) at the image's centre";
    // the buried sphere at (15, 5) is under the terrain: 3/4 across, 3/4 down the image
    EXPECT_TRUE(greyish_or_terrain(img.at(150, 150)));
    EXPECT_TRUE(greyish_or_terrain(img.at(20, 20)));
    // obliquely the sphere on the terrain is still drawn, the frame not blank
    d.camera = TerrainCamera::Oblique;
    const Image oblique = render_terrain(scene, d);
    int violet = 0, white = 0;
    for (int y = 0; y < oblique.height; ++y)
        for (int x = 0; x < oblique.width; ++x) {
            const uint8_t* p = oblique.at(x, y);
            violet += p[2] > p[0] && p[1] < p[0];  // (the terrain's tints have g >= r or r > b)
            white += p[0] == 255 && p[1] == 255 && p[2] == 255;
        }
    EXPECT_GT(violet, 100);
    EXPECT_GT(white, 100);                        // the sky around the tilted square
    EXPECT_LT(white, oblique.width * oblique.height);
}

TEST(TerrainView, FieldOverHillshade) {
    EsriGrid g;
    g.ncols = 3;
    g.nrows = 2;
    g.cellsize = 5.0;
    g.z.assign(6, 100.0);  // flat: the shade is the sun's height, sin 45 deg
    std::vector<double> field(6, 0.0);
    field[5] = 2.0;        // the north-east cell (row 1, col 2): the image's top right
    const Image img = raster_over_hillshade(g, field, 2.0, 4);
    ASSERT_EQ(img.width, 12);
    ASSERT_EQ(img.height, 8);
    const int grey = int(std::lround(255 * (0.25 + 0.75 * std::sqrt(0.5))));
    EXPECT_EQ(img.at(0, 7)[0], grey);
    EXPECT_EQ(img.at(0, 7)[1], grey);
    const uint8_t* hot = img.at(11, 0);  // viridis' top, yellow, over the grey
    EXPECT_EQ(hot[0], int(std::lround(255 * (0.25 * (0.25 + 0.75 * std::sqrt(0.5)) + 0.75 * 0.993))));
    EXPECT_GT(hot[1], hot[2]);
}
