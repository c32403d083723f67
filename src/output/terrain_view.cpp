#include "output/terrain_view.h"

#include <GL/gl.h>
#include <GL/osmesa.h>

#include <algorithm>
#include <cmath>

#include "core/error.h"
#include "core/vec2.h"
#include "output/colour_map.h"

namespace demlab {

namespace {

// A unit icosphere (the icosahedron split once: 80 faces), the spheres' shape in a frame.
struct UnitBall {
    std::vector<Vec3> corners;  // three a face, unit vectors (also the normals)
    UnitBall() {
        const double t = (1.0 + std::sqrt(5.0)) / 2.0;
        std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                               {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
        const int f[20][3] = {{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                              {11, 10, 2}, {10, 7, 6}, {7, 1, 8},  {3, 9, 4},  {3, 4, 2},   {3, 2, 6}, {3, 6, 8},
                              {3, 8, 9},  {4, 9, 5},  {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}};
        for (auto& p : v) p.normalize();
        for (const auto& tri : f) {
            const Vec3 a = v[size_t(tri[0])], b = v[size_t(tri[1])], c = v[size_t(tri[2])];
            const Vec3 ab = (a + b).normalized(), bc = (b + c).normalized(), ca = (c + a).normalized();
            for (const Vec3& q : {a, ab, ca, ab, b, bc, ca, bc, c, ab, bc, ca}) corners.push_back(q);
        }
    }
};

// The camera: orthographic, looking along -towards_viewer; x right, y up on the image.
struct Camera {
    Vec3 right, up, towards_viewer;
    double exaggeration;
    Vec3 eye(const Vec3& p) const {
        const Vec3 q(p.x(), p.y(), p.z() * exaggeration);
        return Vec3(right.dot(q), up.dot(q), towards_viewer.dot(q));
    }
};

Camera camera_of(const TerrainViewDef& d) {
    Camera c;
    c.exaggeration = d.vertical_exaggeration;
    if (d.camera == TerrainCamera::Map) {
        c.right = Vec3(1, 0, 0);
        c.up = Vec3(0, 1, 0);
        c.towards_viewer = Vec3(0, 0, 1);
        return c;
    }
    const double az = deg_to_rad(d.azimuth_deg), el = deg_to_rad(d.elevation_deg);
    c.towards_viewer = Vec3(std::sin(az) * std::cos(el), std::cos(az) * std::cos(el), std::sin(el));
    c.right = Vec3(0, 0, 1).cross(c.towards_viewer).normalized();
    c.up = c.towards_viewer.cross(c.right);
    return c;
}

// terrain colour by height fraction: green low, brown and grey high
Rgb terrain_tint(double f) {
    const Rgb lo{0.55, 0.66, 0.45}, mid{0.70, 0.60, 0.45}, hi{0.85, 0.83, 0.80};
    auto mix = [](const Rgb& a, const Rgb& b, double t) { return Rgb{a.r + t * (b.r - a.r), a.g + t * (b.g - a.g), a.b + t * (b.b - a.b)}; };
    f = std::clamp(f, 0.0, 1.0);
    return f < 0.5 ? mix(lo, mid, 2 * f) : mix(mid, hi, 2 * f - 1);
}

struct MesaContext {
    OSMesaContext ctx = nullptr;
    std::vector<uint8_t> buffer;
    MesaContext(int w, int h) {
        ctx = OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr);
        if (!ctx) throw RunError("OSMesa could not create an off-screen OpenGL context");
        buffer.assign(size_t(w) * size_t(h) * 4, 0);
        if (!OSMesaMakeCurrent(ctx, buffer.data(), GL_UNSIGNED_BYTE, w, h)) throw RunError("OSMesa could not bind the frame buffer");
    }
    ~MesaContext() { OSMesaDestroyContext(ctx); }
};

}  // namespace

Image render_terrain(const TerrainScene& scene, const TerrainViewDef& def) {
    if (def.width < 16 || def.height < 16 || def.width > 8192 || def.height > 8192 || def.supersample < 1 || def.supersample > 4)
        throw InputError("a terrain frame must be 16 to 8192 px a side, supersampled 1 to 4 times");
    if (!scene.vertices || !scene.triangles) throw InputError("a terrain frame needs its terrain");
    const Camera cam = camera_of(def);
    const Vec3 sun = def.sun.normalized();
    const int ss = def.supersample, w = def.width * ss, h = def.height * ss;
    MesaContext mesa(w, h);

    // the view: the terrain's and the spheres' box in the camera's frame, widened to the aspect
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    double zmin = INFINITY, zmax = -INFINITY;
    for (const Vec3& p : *scene.vertices) {
        const Vec3 e = cam.eye(p);
        lo = lo.cwiseMin(e);
        hi = hi.cwiseMax(e);
        zmin = std::min(zmin, p.z());
        zmax = std::max(zmax, p.z());
    }
    for (size_t i = 0; i < scene.centres.size(); ++i) {
        const Vec3 e = cam.eye(scene.centres[i]);
        lo = lo.cwiseMin(e - Vec3::Constant(scene.radius[i]));
        hi = hi.cwiseMax(e + Vec3::Constant(scene.radius[i]));
    }
    const Vec3 pad = 0.03 * (hi - lo) + Vec3::Constant(1e-6);
    lo -= pad;
    hi += pad;
    double sx = hi.x() - lo.x(), sy = hi.y() - lo.y();
    const double aspect = double(def.width) / double(def.height);
    if (sx / sy < aspect) {
        const double grow = sy * aspect - sx;
        lo.x() -= grow / 2;
        hi.x() += grow / 2;
    } else {
        const double grow = sx / aspect - sy;
        lo.y() -= grow / 2;
        hi.y() += grow / 2;
    }

    glViewport(0, 0, w, h);
    glClearColor(1, 1, 1, 1);
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LEQUAL);
    glMatrixMode(GL_PROJECTION);
    glLoadIdentity();
    // eye z: larger is nearer the viewer, who looks down -z as OpenGL's eye does
    glOrtho(lo.x(), hi.x(), lo.y(), hi.y(), -hi.z(), -lo.z());
    glMatrixMode(GL_MODELVIEW);
    glLoadIdentity();

    // the terrain: each face by its slope towards the sun, tinted by its height
    glBegin(GL_TRIANGLES);
    const std::vector<Vec3>& v = *scene.vertices;
    for (const auto& t : *scene.triangles) {
        const Vec3 &a = v[t[0]], &b = v[t[1]], &c = v[t[2]];
        Vec3 n = (b - a).cross(c - a);
        n.z() /= std::max(def.vertical_exaggeration, 1e-9);
        n.normalize();
        if (n.z() < 0) n = -n;
        const double shade = 0.35 + 0.65 * std::max(0.0, n.dot(sun));
        const Rgb tint = terrain_tint(zmax > zmin ? ((a.z() + b.z() + c.z()) / 3 - zmin) / (zmax - zmin) : 0.0);
        glColor3d(tint.r * shade, tint.g * shade, tint.b * shade);
        for (const Vec3* p : {&a, &b, &c}) {
            const Vec3 e = cam.eye(*p);
            glVertex3d(e.x(), e.y(), e.z());
        }
    }
    glEnd();

    // the spheres: balls lit by the same sun, coloured by speed (or rock grey)
    static const UnitBall ball;
    glBegin(GL_TRIANGLES);
    for (size_t i = 0; i < scene.centres.size(); ++i) {
        const Rgb base = scene.speed.empty() ? Rgb{0.55, 0.45, 0.40} : viridis(scene.speed[i], def.speed_max);
        const Vec3 c = cam.eye(scene.centres[i]);
        for (const Vec3& u : ball.corners) {
            const Vec3 world_normal = u;
            const double shade = 0.3 + 0.7 * std::max(0.0, world_normal.dot(sun));
            glColor3d(base.r * shade, base.g * shade, base.b * shade);
            // the ball in the camera's frame: the unit vector turned by the camera, not exaggerated
            const Vec3 e = c + scene.radius[i] * Vec3(cam.right.dot(u), cam.up.dot(u), cam.towards_viewer.dot(u));
            glVertex3d(e.x(), e.y(), e.z());
        }
    }
    glEnd();
    if (!scene.bonds.empty()) {
        glBegin(GL_LINES);
        glColor3d(0.12, 0.20, 0.40);
        for (const auto& [a, b] : scene.bonds)
            for (uint32_t k : {a, b}) {
                const Vec3 e = cam.eye(scene.centres[k]);
                glVertex3d(e.x(), e.y(), e.z() + 1e-3);
            }
        glEnd();
    }
    glFinish();
    return box_filter_down(mesa.buffer.data(), w, h, ss);
}

void attach_terrain_pictures(RunOptions& ro) {
    ro.terrain_frames = [](const std::string& dir, const std::string& tag, const Tin& terrain, const std::vector<Vec3>& centres,
                           const std::vector<double>& radius, const std::vector<double>& speed, double speed_max) {
        TerrainScene scene;
        scene.vertices = &terrain.vertices();
        scene.triangles = &terrain.triangles();
        scene.centres = centres;
        scene.radius = radius;
        scene.speed = speed;
        TerrainViewDef view;
        view.speed_max = speed_max;
        write_png(dir + "/frames/oblique_" + tag + ".png", render_terrain(scene, view));
        view.camera = TerrainCamera::Map;
        write_png(dir + "/frames/map_" + tag + ".png", render_terrain(scene, view));
    };
    ro.raster_picture = [](const std::string& png, const EsriGrid& terrain, const std::vector<double>& field, double field_max) {
        // about 1,000 px across
        const int scale = std::clamp(1000 / std::max(terrain.ncols, 1), 1, 16);
        write_png(png, raster_over_hillshade(terrain, field, field_max, scale));
    };
}

Image raster_over_hillshade(const EsriGrid& g, const std::vector<double>& field, double field_max, int scale) {
    if (scale < 1 || scale > 64 || g.ncols < 1 || g.nrows < 1) throw InputError("a raster picture needs a grid and 1 to 64 px a cell");
    Image img;
    img.width = g.ncols * scale;
    img.height = g.nrows * scale;
    img.rgb.assign(size_t(img.width) * size_t(img.height) * 3, 255);
    // the sun from the north-west (azimuth 315 deg), 45 deg high: ESRI's hillshade default
    const Vec3 sun = Vec3(-0.5, 0.5, std::sqrt(0.5)).normalized();
    auto z = [&](int c, int r) { return g.z[size_t(r) * size_t(g.ncols) + size_t(c)]; };
    auto valid = [&](int c, int r) { return c >= 0 && r >= 0 && c < g.ncols && r < g.nrows && !(g.has_nodata && z(c, r) == g.nodata); };
    for (int r = 0; r < g.nrows; ++r)
        for (int c = 0; c < g.ncols; ++c) {
            if (!valid(c, r)) continue;
            // central differences, one-sided at the edges and beside NODATA
            const int cl = valid(c - 1, r) ? c - 1 : c, cr = valid(c + 1, r) ? c + 1 : c;
            const int rd = valid(c, r - 1) ? r - 1 : r, ru = valid(c, r + 1) ? r + 1 : r;
            const double dzdx = cr > cl ? (z(cr, r) - z(cl, r)) / ((cr - cl) * g.cellsize) : 0.0;
            const double dzdy = ru > rd ? (z(c, ru) - z(c, rd)) / ((ru - rd) * g.cellsize) : 0.0;
            const double shade = std::max(0.0, Vec3(-dzdx, -dzdy, 1.0).normalized().dot(sun));
            double R = 0.25 + 0.75 * shade, G = R, B = R;
            const double f = field[size_t(r) * size_t(g.ncols) + size_t(c)];
            if (f > 0.0) {
                const Rgb col = viridis(f, field_max);
                R = 0.25 * R + 0.75 * col.r;
                G = 0.25 * G + 0.75 * col.g;
                B = 0.25 * B + 0.75 * col.b;
            }
            const uint8_t px[3] = {uint8_t(std::lround(255 * std::clamp(R, 0.0, 1.0))), uint8_t(std::lround(255 * std::clamp(G, 0.0, 1.0))),
                                   uint8_t(std::lround(255 * std::clamp(B, 0.0, 1.0)))};
            // row 0 of the grid is the southernmost: the image's bottom
            for (int y = 0; y < scale; ++y)
                for (int x = 0; x < scale; ++x) {
                    uint8_t* p = img.at(c * scale + x, (g.nrows - 1 - r) * scale + y);
                    p[0] = px[0];
                    p[1] = px[1];
                    p[2] = px[2];
                }
        }
    return img;
}

}  // namespace demlab
