// demlab demo: a small built-in dam break (a column of discs behind a gate that is removed),
// writing energy and wall-force time series. Exercises every part of the engine in seconds.
#include <chrono>
#include <cstdio>
#include <fstream>
#include <memory>
#include <random>
#include <sstream>
#include <string>

#include "app/commands.h"
#include "core/fileio.h"
#include "core/error.h"
#include "core/output_dir.h"
#include "core/progress.h"
#include "core/validate.h"
#include "dem/world.h"
#include "run/run.h"

namespace demlab {

namespace {
struct DemoOptions {
    std::string out = "runs/demo";
    bool force = false;
    double t_end = 1.0;
    int model = 3;
    long long seed = 1;  // signed: "-1" would wrap to 2^64 - 1 in an unsigned option
};

// Uniform in [0, 1) from the top 53 bits: the same numbers on every platform (the standard
// distributions are implementation-defined).
double uniform01(std::mt19937_64& rng) { return double(rng() >> 11) * 0x1.0p-53; }

int demo(const DemoOptions& o) {
    require_positive("demo --t-end", o.t_end, "s");
    if (o.seed < 0) throw InputError("demo --seed " + std::to_string(o.seed) + ": must be an integer >= 0");
    const double width = 0.10, height = 0.20, r_min = 0.002, r_max = 0.003, t_settle = 0.3;

    WorldDef def;
    def.rotation.model = o.model;
    def.domain_lo = Vec2(-0.1, -0.1);
    def.domain_hi = Vec2(2.0, 1.0);
    World world(def);
    const int sand = world.add_material(MaterialDef{});
    std::mt19937_64 rng(static_cast<unsigned long long>(o.seed));
    const double pitch = 2.0 * r_max * 1.02;
    // hexagonal rows (each row shifted by half a pitch), so the column can collapse
    int row = 0;
    for (double y = pitch / 2; y < height; y += pitch * 0.8660254037844386, ++row)
        for (double x = pitch / 2 + (row % 2) * pitch / 2; x + pitch / 2 < width; x += pitch)
            world.add_disc({Vec2(x, y), r_min + (r_max - r_min) * uniform01(rng), Vec2::Zero(), 0.0, 0.0, sand});
    WallDef floor;
    floor.name = "floor";
    floor.p0 = Vec2(-0.01, 0.0);
    floor.p1 = Vec2(1.0, 0.0);
    floor.segment_solid = SegmentSolid::Right;
    WallDef back = floor;
    back.name = "back";
    back.p0 = Vec2(0.0, 0.4);
    back.p1 = Vec2(0.0, -0.01);
    WallDef gate = back;
    gate.name = "gate";
    gate.segment_solid = SegmentSolid::Both;
    gate.p0 = Vec2(width, 0.4);
    gate.p1 = Vec2(width, 0.0005);
    gate.remove_at = t_settle;
    world.add_wall(floor);
    world.add_wall(back);
    world.add_wall(gate);
    world.set_local_damping(0.7);
    world.finalize();
    // the absurd-steps guard of `demlab run` (run.cpp), before the folder is made: a --t-end
    // of 1e300 s ran until killed
    if (o.t_end / world.dt() > kMaxRunSteps)
        throw InputError("demo --t-end " + format_number(o.t_end) + " s would take " + format_number(o.t_end / world.dt()) +
                         " steps of " + format_number(world.dt()) + " s (more than " + format_number(kMaxRunSteps) + ")");
    prepare_output_dir(o.out, o.force);

    SeriesFile series_file;  // checked writes, a final name only when complete
    series_file.open(o.out + "/series.csv");
    std::ostream& series = series_file.out();
    series.precision(6);  // (the demo's figures as they always were)
    series << "t,kinetic_J,potential_J,elastic_J,dissipated_J,balance_J,floor_fx_N,floor_fy_N,back_fx_N,back_fy_N,"
              "gate_fx_N,gate_fy_N\n";
    const auto t0 = std::chrono::steady_clock::now();
    Progress progress(o.t_end);
    double next_out = 0.0;
    bool released = false;
    while (world.time() < o.t_end) {
        if (!released && world.time() >= t_settle) {
            world.set_local_damping(0.0);
            released = true;
        }
        world.step();
        if (world.time() >= next_out) {
            const EnergyReport e = world.energy();
            series << world.time() << ',' << e.kinetic_translation + e.kinetic_rotation << ',' << e.potential << ','
                   << e.elastic << ',' << e.dissipated_contacts + e.dissipated_local + e.dissipated_rotation << ','
                   << e.balance();
            for (int w = 0; w < 3; ++w) series << ',' << world.wall_force(w).x() << ',' << world.wall_force(w).y();
            series << '\n';
            next_out += 0.005;
        }
        progress.update(world.time(), world.step_count());
    }
    progress.finish();
    const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    series_file.close();
    std::ostringstream final_discs;
    final_discs << "id,x_m,y_m,r_m,vx_m_s,vy_m_s,omega_rad_s\n";
    double runout = 0.0;
    for (size_t i = 0; i < world.disc_count(); ++i) {
        const Vec2& p = world.positions()[i];
        const Vec2& v = world.velocities()[i];
        final_discs << i << ',' << p.x() << ',' << p.y() << ',' << world.radii()[i] << ',' << v.x() << ',' << v.y()
                    << ',' << world.omegas()[i] << '\n';
        runout = std::max(runout, p.x() + world.radii()[i]);
    }
    write_file_atomic(o.out + "/final_discs.csv", final_discs.str());
    std::printf("demo: %zu discs, model %d, %ld steps to t = %.3f s (dt %.3g s) in %.2f s wall, %.3e particle-steps/s\n",
                world.disc_count(), o.model, world.step_count(), world.time(), world.dt(), secs,
                double(world.disc_count()) * double(world.step_count()) / secs);
    std::printf("  front of the deposit at x = %.3f m; weight carried by the floor %.2f N/m of %.2f N/m\n", runout,
                -world.wall_force(0).y(), [&] {
                    double m = 0;
                    for (double mi : world.masses()) m += mi;
                    return m * 9.81;
                }());
    std::printf("  wrote %s/series.csv and %s/final_discs.csv\n", o.out.c_str(), o.out.c_str());
    remove_replaced_output(o.out);
    return kExitOk;
}
}  // namespace

Command add_demo_command(CLI::App& app) {
    auto opts = std::make_shared<DemoOptions>();
    CLI::App* sub = app.add_subcommand("demo", "A small built-in dam break: settles a column, removes the gate, runs");
    sub->add_option("--out", opts->out, "Output folder (must not exist unless --force)")->capture_default_str();
    sub->add_flag("--force", opts->force, "Replace the files of an existing output folder");
    sub->add_option("--t-end", opts->t_end, "Simulated time, s")->capture_default_str();
    sub->add_option("--model", opts->model, "Rotation model 1, 2 or 3")->capture_default_str()->check(CLI::Range(1, 3));
    sub->add_option("--seed", opts->seed, "Seed of the disc radii")->capture_default_str();
    return [opts] { return demo(*opts); };
}

}  // namespace demlab
