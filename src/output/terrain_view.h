// Pictures of a 3-D run: off-screen frames of a triangulated terrain, shaded, with the spheres
// on it (OSMesa, no display and no GPU, as the 2-D frames), from an oblique view or from above;
// and a peak raster over the terrain's hillshade, as AvaFrame shows its result fields.
#pragma once
#include <array>
#include <cstdint>
#include <string>
#include <utility>
#include <vector>

#include "core/vec3.h"
#include "geometry/esri_grid.h"
#include "output/image.h"
#include "run/run.h"

namespace demlab {

struct TerrainScene {
    const std::vector<Vec3>* vertices = nullptr;                          // m, the TIN's
    const std::vector<std::array<std::uint32_t, 3>>* triangles = nullptr;  // its faces
    std::vector<Vec3> centres;                                            // m, the spheres'
    std::vector<double> radius;                                           // m
    std::vector<double> speed;                                            // m/s, the colour (empty: one colour)
    std::vector<std::pair<std::uint32_t, std::uint32_t>> bonds;           // intact bonds, drawn as lines
};

enum class TerrainCamera { Oblique, Map };

struct TerrainViewDef {
    int width = 1280;                   // px
    int height = 720;                   // px
    int supersample = 2;                // drawn at this factor, then averaged down
    TerrainCamera camera = TerrainCamera::Oblique;
    double azimuth_deg = 210.0;         // deg, the direction the viewer looks from, clockwise from north (+y)
    double elevation_deg = 35.0;        // deg, above the horizon (the map view: 90)
    double vertical_exaggeration = 1.0;  // -
    double speed_max = 50.0;            // m/s, the top of the speed colours
    Vec3 sun = Vec3(-0.5, 0.6, 0.62);   // towards the light (normalised when used): from the north-west, high
};

// The terrain shaded by its slope towards the sun, tinted by height, with the spheres shaded
// as balls (coloured by speed); the view fits the terrain's box.
Image render_terrain(const TerrainScene& scene, const TerrainViewDef& def);

// A 3-D run's pictures (RunOptions::terrain_frames, raster_picture) drawn by these functions.
void attach_terrain_pictures(RunOptions& ro);

// A field on g's cells over g's hillshade (sun from the north-west at 45 deg): cells with a
// value above 0 coloured from 0 to field_max (viridis), the rest grey; `scale` pixels a cell.
Image raster_over_hillshade(const EsriGrid& terrain, const std::vector<double>& field, double field_max, int scale);

}  // namespace demlab
