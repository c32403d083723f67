// The simulated world: discs (structure of arrays), walls, the contact lists and the time
// loop. One step (PFC's cycle, thesis Fig. 8): broad phase, contact forces (linear law),
// time step, central-difference motion with the chosen rotation model, wall motion.
#pragma once
#include <atomic>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "dem/broad_phase.h"
#include "dem/centre_lanes.h"
#include "dem/integrate_kernel.h"
#include "dem/laws/contact_law.h"
#include "dem/material.h"
#include "dem/bonds/elastic_bond.h"
#include "dem/laws/contact_laws.h"
#include "dem/laws/pair_kernel.h"
#include "dem/laws/wall_kernel.h"
#include "dem/range_balance.h"
#include "dem/rotation.h"
#include "core/vec2.h"
#include "geometry/wall.h"

namespace demlab {

class ThreadPool;
class BinaryWriter;
class BinaryReader;

struct DampingDef {
    double beta_n = 0.5;                   // -, normal critical damping ratio in [0, 1) (Table 15)
    double beta_s = 0.5;                   // -, shear critical damping ratio in [0, 1)
    DashpotMode dp_mode = DashpotMode::Full;
    double local_alpha = 0.0;              // -, PFC local damping (eq. 2.51) in [0, 1); the settling, and the flow if damping.local_alpha is set
};

// How the linear law's dashpots are integrated (docs/engine.md, "Dashpots"): at the step's
// centre, from the velocities the step's other forces lead to (stable at PFC's step rule as
// printed), or lagged, from the velocities half a step back (the scheme of earlier builds,
// which needs the damping correction of timestep.h).
enum class DashpotScheme { Centred, Lagged };

struct TimeStepDef {
    bool automatic = true;                 // PFC rule (timestep.h); false: the fixed step below
    double safety = 0.8;                   // -, safety factor of the automatic step, (0, 1]
    double fixed = 1.0e-6;                 // s, used when automatic = false
    DashpotScheme dashpots = DashpotScheme::Centred;
    bool damping_correction = true;        // shrink the bounds for local damping and lagged dashpots (timestep.h)
};

// What happens to a disc whose centre leaves the domain (WorldDef::domain_lo/hi): the run
// stops with an error, or the disc is taken out at the end of the step (World::lost_discs).
enum class LostDiscs { Stop, Remove };

// Software prefetch in the force pass and the centre pass: Auto turns it on when the step's
// arrays outgrow the cache (World::prefetching), On and Off force it (benchmarks, tests).
enum class Prefetch { Auto, Off, On };
// the bytes a step must stream (World::step_bytes) above which Auto prefetches
size_t prefetch_threshold_bytes();

// Renumbering the discs in space order as they flow (space_order.cpp): Auto does it in worlds
// of more than kSpaceOrderFlowDiscs discs without bonds, On in any world without bonds.
enum class SpaceOrder { Auto, On, Off };
// Above this many discs a world's arrays outgrow the caches, and a contact's second disc out
// of order is a miss: geometry A at scale 2 (36,400) and 1 (145,615), not 4 (9,101); the
// releases below 20,000 discs and the regression references keep their bits.
constexpr size_t kSpaceOrderFlowDiscs = 20000;

struct WorldDef {
    ContactLawKind law = law_kind<LinearLaw>();  // the contact law of every contact (contact_laws.h)
    Vec2 gravity{0.0, -9.81};              // m/s2
    DampingDef damping;
    TimeStepDef timestep;
    RotationDef rotation;
    FrictionRule friction_rule_disc_disc = FrictionRule::Min;  // PFC default
    FrictionRule friction_rule_disc_wall = FrictionRule::Max;  // thesis, section 4.3.2
    double broadphase_margin = 0.0;        // m, pad of the fat boxes; 0 = half the smallest radius
    double wall_piece_length = 0.0;        // m, walls are cut into pieces this long for the broad phase;
                                           // 0 = six times the largest radius (three diameters)
    double joint_tolerance = 1.0e-3;       // m, wall ends closer than this are joined (snapped)
    double max_overlap_ratio = 0.5;        // -, an overlap beyond this fraction of the smaller radius stops the run
    Vec2 domain_lo{-1e30, -1e30};          // m, a disc centre leaving [lo, hi] is lost: see lost_discs
    Vec2 domain_hi{1e30, 1e30};
    LostDiscs lost_discs = LostDiscs::Stop;  // a lost disc stops the run, or is taken out (lost_discs.cpp)
    int threads = 1;                       // worker threads; results are the same bits for any count
    bool simd = true;                      // the disc-disc kernel 4 pairs at a time when the CPU has AVX2
                                           // (pair_kernel_avx2.cpp); the same bits as the scalar kernel
    bool avx512 = true;                    // with simd: its law 8 pairs and its integration 8 discs at a time
                                           // when the CPU has AVX-512 (pair_kernel_avx512.cpp,
                                           // integrate_avx512.cpp); the same bits again
    BondDef bond;                          // the bonds' law (World::add_bond), if any bonds are added
    AllLawDefs laws;                       // each registered law's own keys (DebrisLaw: its modulus,
                                           // friction and step ceiling; law_def<Law>())
    Prefetch prefetch = Prefetch::Auto;    // the force pass asks for its arrays' lines ahead of use
                                           // (force_pass.cpp, kPrefetchContacts); never changes a result
    SpaceOrder space_order = SpaceOrder::Auto;  // renumber the discs in space order as they flow
    int space_order_steps = 20000;         // -, steps between renumberings, >= 1

    template <typename Law>
    typename Law::Def& law_def() { return std::get<size_t(law_kind<Law>())>(laws); }
    template <typename Law>
    const typename Law::Def& law_def() const { return std::get<size_t(law_kind<Law>())>(laws); }
};

void validate(const WorldDef& d, const std::string& where);

struct DiscDef {
    Vec2 pos{0.0, 0.0};                    // m
    double radius = 0.0;                   // m, > 0
    Vec2 vel{0.0, 0.0};                    // m/s
    double omega = 0.0;                    // rad/s, counter-clockwise
    double angle = 0.0;                    // rad
    int material = 0;                      // index returned by add_material
    Vec2 force{0.0, 0.0};                  // N/m, a constant force added every step (tests, loads)
};

// Energies of the current state and what was dissipated so far, J per metre of thickness.
// Central differences keep velocities at half steps, so the ledger is centred too: kinetic
// energy from v(t - dt/2), potential energy at t - dt/2 (mean of the last two positions), and
// a dashpot's work as its force times the mean of the relative velocities before and after
// the step (the displacement (x(t+dt) - x(t-dt)) / 2 it acts over).
struct EnergyReport {
    double kinetic_translation = 0, kinetic_rotation = 0, potential = 0, elastic = 0;
    double dissipated_contacts = 0;   // dashpots and sliding
    double dissipated_local = 0;      // local damping
    double dissipated_rotation = 0;   // rolling resistance and rotational damping
    double work_by_walls = 0;         // work done on the discs by moving walls
    double removed_with_walls = 0;    // elastic energy of contacts lost when a wall was removed
    double bond_elastic = 0;          // elastic energy of the intact bonds (elastic_bond.h, C7)
    double bond_break_loss = 0;       // energy the bonds held when they broke (C12)
    double lost_with_discs = 0;       // energy the lost discs took out (kinetic, potential, contacts, bonds)
    double lost_potential = 0;        // its potential part (energy_put_in needs it)
    // Balance: kinetic + potential + elastic + dissipated - work_by_walls should stay constant.
    double balance() const {
        double b = kinetic_translation + kinetic_rotation + potential + elastic + dissipated_contacts +
                   dissipated_local + dissipated_rotation + removed_with_walls - work_by_walls;
        // (added only with bonds: a world without them keeps the bits it had)
        if (bond_elastic != 0.0 || bond_break_loss != 0.0) b += bond_elastic + bond_break_loss;
        if (lost_with_discs != 0.0) b += lost_with_discs;  // (the same: only after a disc was lost)
        return b;
    }
};

// A disc taken out of the world (LostDiscs::Remove): when, which (its index when added), its
// state then, and the energy it took out of the ledger (J/m).
struct LostDiscEvent {
    double t;
    int32_t id;
    Vec2 pos, vel;
    double omega, mass, energy;
};

class World {
public:
    explicit World(const WorldDef& def = WorldDef{});
    ~World();
    World(World&&) noexcept;

    // A material of discs or of walls; its index is what DiscDef::material and
    // WallDef::material refer to. Add the discs' materials first: the disc-disc tables cover
    // the materials up to the last one a disc has (disc_materials_), a wall's material after
    // them only its disc-wall entries.
    int add_material(const MaterialDef& m);
    int add_disc(const DiscDef& d);
    int add_wall(const WallDef& w);
    // A bond between discs k and l (elastic_bond.h, WorldDef::bond), its rest length the
    // distance at finalize(). Bonds are persistent: they do not depend on the broad phase,
    // act at any distance beside the contacts, and are saved in checkpoints.
    int add_bond(int k, int l);
    // Checks the whole set-up, joins wall ends, builds the broad phase and the first time step.
    void finalize();

    void step();
    void run(long steps);

    // --- state (read-only views) ---
    size_t disc_count() const { return pos_.size(); }
    size_t wall_count() const { return walls_.size(); }
    double time() const { return time_; }
    double dt() const { return dt_; }
    long step_count() const { return steps_; }
    const WorldDef& def() const { return def_; }

    const std::vector<Vec2>& positions() const { return pos_; }
    const std::vector<Vec2>& velocities() const { return vel_; }
    const std::vector<double>& radii() const { return radius_; }
    const std::vector<double>& masses() const { return mass_; }
    const std::vector<double>& angles() const { return angle_; }
    const std::vector<double>& omegas() const { return omega_; }
    Vec2 force(size_t i) const { return load_[i].force; }      // contact force of the last step, N/m
    double torque(size_t i) const { return load_[i].torque; }  // contact torque of the last step, N m/m
    const std::vector<DiscContact>& disc_contacts() const { return dd_; }
    const std::vector<WallContact>& wall_contacts() const { return dw_; }
    const std::vector<Bond>& bonds() const { return bonds_; }                // sorted by (k, l)
    const std::vector<BondBreakEvent>& bond_breaks() const { return bond_breaks_; }  // in order, disc ids
    // The index each disc had when it was added (disc_ids()[i] == i until a disc is lost or
    // the discs are renumbered in space order), the discs taken out in order, and the bonds: how many there were at
    // finalize() and how many intact ones went with lost discs (bonds() holds the others).
    const std::vector<int32_t>& disc_ids() const { return id_; }
    const std::vector<LostDiscEvent>& lost_discs() const { return lost_; }
    size_t bonds_at_start() const { return bonds_at_start_; }
    size_t bonds_lost_with_discs() const { return bonds_lost_; }
    // the present index of the disc added as `id`, or -1 if it was lost
    long disc_index(long id) const;
    // how many times the discs were renumbered in space order (WorldDef::space_order)
    long space_orderings() const { return space_orderings_; }
    const WallDef& wall_def(int w) const { return walls_[size_t(w)]; }
    const WallGeom& wall_geom(int w) const { return geom_[size_t(w)]; }
    bool wall_active(int w) const { return wall_active_[size_t(w)] != 0; }

    // Force (N per metre of thickness) and moment about the origin (N m / m) that the discs
    // exert on wall w, summed over its contacts in the last step.
    Vec2 wall_force(int w) const { return wall_force_[size_t(w)]; }
    // The touching disc-wall contacts of the last step, in the order wall_force sums them:
    // the disc (its index now), the wall, and the disc's force on the wall, N/m. Their sum
    // over a wall's contacts is wall_force. (The barrier's pressure and the bed's: measures.)
    struct WallLoad {
        int32_t disc, wall;
        Vec2 force;
    };
    void wall_loads(std::vector<WallLoad>& out) const;
    double wall_moment(int w) const { return wall_moment_[size_t(w)]; }
    // Time integral of wall_force since the start, N s / m.
    Vec2 wall_impulse(int w) const { return wall_impulse_[size_t(w)]; }

    // Number of disc-disc and disc-wall contacts with overlap in the last step.
    long touching_disc_pairs() const { return touching_dd_; }
    long touching_wall_pairs() const { return touching_dw_; }

    EnergyReport energy() const;
    // The discs' kinetic energy after the last step, J/m: sum of 0.5 m |v|^2 + 0.5 I omega^2
    // (no rotation term when rotation is locked), added up by the integration per block of
    // discs and the blocks in order, so the same bits for any thread count, at no serial
    // cost (the run's rest and blow-up watch reads it every 10 steps). Not updated by the
    // direct edits below; 0 before the first step.
    double kinetic_energy() const { return kinetic_; }
    // The force pass's split (force_pass_ranges.cpp): disc ranges (one per thread when shared out) and how
    // many candidate pairs cross from one range to another (computed into slots first).
    int force_pass_ranges() const { return force_ranges_; }
    bool simd_kernel() const { return avx2_; }  // the AVX2 kernels are in use (pair forces, integration)
    bool avx512_kernel() const { return avx512_; }  // and the pair law and integration run eight at a time (AVX-512)
    // whether the force pass prefetches (WorldDef::prefetch), and the bytes its step streams through
    bool prefetching() const;
    size_t step_bytes() const;
    size_t cross_contacts() const { return cross_.size(); }
    // disc-disc candidates the AVX2 pass skipped by the clearance test (PairSkip), summed over
    // the steps, and the approach bound now, m
    long pairs_skipped() const { return pairs_skipped_; }
    long candidate_passes() const { return candidate_passes_; }  // disc-disc candidates, summed over the force passes
    double approach() const { return approach_; }
    // per range: its share of the work model (discs + owned contacts) after the measured
    // balancing, and how often the ranges were re-cut to balance their times
    const std::vector<double>& force_pass_shares() const { return range_share_; }
    long force_pass_rebalances() const { return rebalances_; }
    // Wall-clock seconds in the steps' candidate-list updates (broad phase and contact lists),
    // summed: mostly the calling thread's alone (docs/performance.md).
    double list_update_seconds() const { return list_seconds_; }
    // How often the pass ran as one range although the pool has more threads, because more
    // than the limit's share of the disc-disc candidates crossed between ranges (discs not
    // in space order; split_force_pass). The limit can be set for tests and experiments, from
    // 0 to 1 (1: never one range); no bit depends on it.
    long force_pass_one_range_cuts() const { return one_range_cuts_; }
    // Wall-clock seconds of the force passes that ran as more than one range, summed, and the
    // share of the threads' time in them that the ranges spent working (1 - the share they
    // waited: at the join for the slowest range, for another range's cross contacts, and for
    // the hand-over). 1 when no pass was shared out. The step-to-step balance on a machine
    // whose cores' speeds vary (docs/performance.md).
    double force_pass_shared_seconds() const { return shared_pass_seconds_; }
    double force_pass_busy_share() const;
    void set_cross_share_limit(double share);
    // Re-cuts the ranges in these shares of the work model (one per range, summing to 1; the
    // measured balancing continues from them). For tests and experiments: no bit depends on it.
    void cut_force_pass(const std::vector<double>& shares);
    // Runs the force pass as one range for the next `steps` steps, then cuts it for the pool
    // again. The step does this itself when the ranges worked less than 1 / ranges of the
    // threads' time in BusyWatch::kWindows balancing windows in a row (another process on a core:
    // one_range_would_be_faster, range_balance.h), for kOneRangeSteps; callable for tests and
    // experiments. No bit depends on it.
    void run_as_one_range_for(long steps);
    // Whether the step may fall back so (on by default); off for tests that check the ranges.
    void set_busy_fallback(bool on) { busy_fallback_ = on; }
    // how often the step fell back to one range for a busy machine, and the steps it ran so
    long force_pass_busy_fallbacks() const { return busy_fallbacks_; }
    long force_pass_one_range_steps() const { return one_range_steps_; }
    const BroadPhaseStats& broad_phase_stats() const { return broad_.stats(); }
    double broad_phase_margin() const { return broad_.margin(); }

    // The automatic step for the current contacts (timestep rule, see timestep.h).
    double automatic_dt() const;

    // --- direct edits (tests, generation); call between steps ---
    void set_velocity(int i, const Vec2& v) { vel_[size_t(i)] = v; }
    void set_omega(int i, double w) { omega_[size_t(i)] = w; }
    void set_position(int i, const Vec2& p) {
        pos_[size_t(i)] = p;
        discs_may_have_escaped_ = true;
        forget_clearances();
    }
    void set_dt(double dt);  // switches to a fixed step
    // Changes a disc's radius (mass and inertia follow); call refresh_dashpots() after a batch.
    void set_radius(int i, double r);
    void refresh_dashpots();
    // Multiplies every material's kn and ks by factor (the pair tables, the contacts' dashpots
    // and the automatic step follow): the release's settling raises the stiffness of a mass
    // in equilibrium gradually, which a new world at the higher stiffness would jolt. The
    // Hertz and DEBRIS laws take their stiffness from their own keys and do not read kn, ks.
    void scale_stiffness(double factor);
    // Mean |net force| (contact + gravity) over mean |contact force| of the last step: PFC's
    // equilibrium ratio (0 when nothing touches).
    double unbalanced_force_ratio() const;
    void set_local_damping(double alpha);
    void set_gravity(const Vec2& g) { def_.gravity = g; }

    // --- checkpoints (world_state.cpp) ---
    // Writes the dynamic state: disc motion, time and step, the walls' positions, activity
    // and loads, every contact's history and the energy ledger. load_state() restores it
    // into a world built from the same set-up (same discs, walls and materials; finalized);
    // the continued run then gives the same bits as one never stopped (the candidate lists
    // are rebuilt: see world_state.cpp for why that changes nothing).
    void save_state(BinaryWriter& out) const;
    void load_state(BinaryReader& in);

private:
    struct DtFactors {
        bool rotation_free;
        double phi_sq, phi_t_sq;
    };
    struct IntegrateConsts {
        double dt = 0.0;
        Vec2 g{0.0, 0.0};
        double alpha = 0.0, g_abs = 0.0;
        bool auto_dt = false;
        DtFactors dtf{};
    };
    // The force pass (force_pass.cpp); with then_integrate (a step), each range's discs are
    // integrated as soon as their sums are complete, and integrate_finish() must follow.
    void compute_forces(bool then_integrate = false);
    template <typename Law>
    void compute_forces_with(bool then_integrate);
    // what every range of one pass reads
    template <typename Law>
    struct PassContext {
        DiscArrays discs;
        PairPassParamsT<typename Law::Params> pp;
        IntegrateConsts ic;
        bool then_integrate;
        bool prefetch;
        uint64_t pass;                    // this pass' number (the cross contacts' flags)
        float approach_lo, approach_hi;   // the clearance test's bound (PairSkip)
        bool centred;                     // centred dashpots: each range centres and integrates its
                                          // blocks behind its pass (centred_dashpots.cpp)
    };
    struct WallSum;
    template <typename Law>
    void range_pass(int t, const PassContext<Law>& ctx);
    template <typename Law>
    void compute_cross_contacts(size_t t, const PassContext<Law>& ctx);
    double wait_for_cross(size_t t, uint64_t pass) const;
    struct CrossDone;
    // s spent until flags[u0, u1) all hold this pass
    static double wait_for(const CrossDone* flags, size_t u0, size_t u1, uint64_t pass);
    template <typename Law>
    size_t wall_contacts(size_t& kw, size_t end, int t, const PassContext<Law>& ctx, WallSum* sums, size_t n);
    void block_ledger(size_t b0, size_t b1, size_t t);
    // centred dashpots (centred_dashpots.cpp): each touching contact's dashpot force moved to
    // the step's centre, block by block behind the range's pass, then the block integrated
    bool centred_dashpots() const;
    // the law applies its friction per disc in the integrator (DebrisLaw: integrate_debris.cpp)
    bool disc_friction() const { return with_contact_law(def_.law, [](auto law) { return decltype(law)::kDiscFriction; }); }
    void prepare_centred_pass();
    CentreConsts centre_consts(const PairPassParams& pp) const;
    // range t's touching pairs touching_list_[t][e0, e1): their shifts into dash_ (or, for the
    // discs below late_end, into late_shares_[t]; a cross pair's second share into cross_shift_)
    void centre_rows(size_t t, const PairPassParams& pp, const CentreConsts& k, size_t e0, size_t e1, size_t late_end,
                     size_t& cross_cursor, bool prefetch);
    // range t's wall contacts dw_[kw0, kw1): their shifts into dash_ and their records from
    // wall_sums_[t][e] on; false: a touching contact without its record
    bool centre_walls(size_t t, const CentreConsts& k, size_t kw0, size_t kw1, size_t& e);
    void finish_late_discs(size_t t);  // the cross shifts into range t, then its late shares
    void integrate_centred(size_t b0, size_t b1, int t, const IntegrateConsts& ic);
    struct DashSum {  // a disc's shifts, added to its sums before it moves
        Vec2 force{0.0, 0.0};    // N/m
        double torque = 0.0;     // N m/m
        double dissipated = 0.0; // J/m
    };
    std::vector<DashSum> dash_;
    std::vector<uint8_t> dash_ok_;  // per range: 0 once a wall contact's record was missing
    // A pair's shares kept back for discs that also get cross shifts, which come first in
    // their order (a disc adds its shifts in contact-list order, as the sums)
    struct LateShare {
        int32_t i, j;
        double fx, fy;                // N, on j (i gets the opposite)
        double torque_i, torque_j;    // N m
        double dissipated;            // J
    };
    std::vector<std::vector<LateShare>> late_shares_;  // per range
    struct CrossShift {  // a touching cross contact's share for its second disc
        double fx, fy, torque_j, dissipated;
        uint64_t pass;  // the pass that computed it
    };
    std::vector<CrossShift> cross_shift_;    // per cross contact (cross_ order)
    std::vector<size_t> fuse_touching_end_;  // per FuseBlock: its range's touching pairs so far
    std::vector<size_t> fuse_sums_end_;      // per FuseBlock: its range's wall records so far
    std::vector<std::unique_ptr<CentreBlock>> centre_blocks_;
    struct alignas(64) CentreDisc {
        double vx, vy, w;         // m/s, rad/s at t - dt/2
        double pvx, pvy, pw;      // m/s, rad/s at t from the pass' sums (v*)
        double inv_mass, inv_inertia;
    };
    std::vector<CentreDisc> centre_discs_;
    // per range: the pass' touching pairs among its contacts (its own and its cross ones), in
    // list order, so that the centre pass reads only those
    std::vector<std::vector<uint32_t>> touching_list_;
    void pack_centre_discs(size_t d0, size_t d1);  // their pairs' lanes (centre_lanes.h); dash_ zeroed
    void add_up_pass();
    void copy_cross_contacts();
    void note_disc_fault(size_t k, double overlap, int chunk);
    // the bonds (bonds.cpp): rest lengths and each disc's bonds at finalize; every bond's
    // force into its slot before the ranges; a block's discs' bond terms; the breaks after
    void prepare_bonds();
    void compute_bond_forces();
    template <bool Predict>
    void bond_pass();
    void add_bond_terms(size_t d0, size_t d1);
    void add_external_forces(size_t d0, size_t d1);
    void settle_bond_breaks();
    void book_bond_dashpots();
    double bond_elastic_energy() const;
    void note_wall_fault(size_t kw, double overlap, int chunk);
    IntegrateConsts integrate_prepare();
    void integrate_discs(size_t begin, size_t end, int chunk, const IntegrateConsts& k);
    void integrate_discs_debris(size_t begin, size_t end, int chunk, const IntegrateConsts& k);  // integrate_debris.cpp
    // does integrate_discs use the AVX2 (or AVX-512) loop? (per-disc rotational damping)
    bool avx2_integration() const;
    void integrate_note(int chunk, size_t fault, double best_sq, bool any_escaped, double speed_l1, double extent_l1);
    void integrate_finish();
    void move_walls();
    void refresh_contacts();
    // lost discs (lost_discs.cpp): those outside the domain at the end of a step, taken out
    std::vector<size_t> lost_pending_;
    void take_out_lost_discs();
    // takes the discs `gone` (present indices, ascending) out of every array, list and bond
    void compact_discs(const std::vector<size_t>& gone);
    // disc k becomes the one that was from[k], the others are taken out (lost_discs.cpp)
    void remap_discs(const std::vector<int32_t>& from);
    // the renumbering in space order and when it is due (space_order.cpp)
    bool space_order_due() const;
    void order_discs_in_space();
    long space_order_every_ = 0;  // steps between renumberings, 0: never (finalize)
    long space_orderings_ = 0;
    bool ids_in_order_ = true;             // id_ ascending (disc_index searches it)
    std::vector<int32_t> index_of_id_;     // otherwise: the index of each id, -1 once lost
    // the broad phase and contact lists rebuilt for the present discs, with these histories
    void rebuild_lists(const std::vector<DiscContact>& dd, const std::vector<WallContact>& dw);
    void index_bonds();
    // the parts of the world that depend on the contact law, as templates over it
    template <typename Law>
    void build_law_tables();
    template <typename Law>
    void refresh_contacts_with();
    template <typename Law>
    void refresh_dashpots_with();
    template <typename Law>
    EnergyReport energy_with() const;
    void join_wall_ends();
    double contact_mass_disc(int i, int j) const;
    double margin_target() const;  // m, the broad phase's pad (WorldDef::broadphase_margin)
    double wall_piece_target() const;  // m, the broad phase's longest wall piece (WorldDef::wall_piece_length)
    // the automatic step (timestep.h): its constant factors, one disc's bound, the step
    DtFactors dt_factors() const;
    double critical_step_squared_of(size_t i, const DtFactors& f) const;
    static constexpr long kPadCheckSteps = 128;  // see step()
    static double critical_step_squared_at(const DiscLoad& l, double own_k_tran, double own_k_rot, double mass, double inertia,
                                           double radius, const DtFactors& f);
    double step_from_critical_squared(double best_sq) const;

    WorldDef def_;
    bool finalized_ = false;
    double time_ = 0.0, dt_ = 0.0;
    long steps_ = 0;

    std::vector<MaterialDef> materials_;
    // The materials the discs may have: [0, disc_materials_), from finalize() (1 + the
    // largest a disc has, at least 1). The disc-disc tables are disc_materials_ square, the
    // disc-wall tables disc_materials_ rows of a wall each, and the kernels' n_materials is
    // it (1: every disc reads entry 0, whatever the walls' materials).
    size_t disc_materials_ = 1;
    // every registered law's parameter tables; the chosen law's are filled by finalize()
    AllLawTables law_tables_;
    template <typename Law>
    LawTables<Law>& tables() { return std::get<LawTables<Law>>(law_tables_); }
    template <typename Law>
    const LawTables<Law>& tables() const { return std::get<LawTables<Law>>(law_tables_); }

    // discs, structure of arrays
    std::vector<Vec2> pos_, vel_;
    std::vector<double> radius_, mass_, inv_mass_, inertia_, inv_inertia_, angle_, omega_;
    std::vector<int32_t> material_;
    std::vector<int32_t> id_;           // the index each disc had when added (disc_ids)
    std::vector<LostDiscEvent> lost_;
    double lost_energy_ = 0.0, lost_potential_ = 0.0;  // J/m, the ledger's share of the lost discs
    std::vector<double> rr_factor_;     // Preh-Poisel factor per disc, 1/m (0 without rolling resistance)
    // what each disc's contacts add up to in a step (DiscLoad, pair_kernel.h)
    std::vector<DiscLoad> load_;
    // DebrisLaw: the sum of each disc's bed reactions this step (N/m; its friction's N),
    // zeroed per block before the wall contacts
    std::vector<Vec2> wall_reaction_;

    // walls
    std::vector<WallDef> walls_;
    std::vector<WallGeom> geom_;
    std::vector<uint8_t> wall_active_, wall_moving_;
    std::vector<Vec2> wall_force_, wall_impulse_;
    std::vector<double> wall_moment_;

    BroadPhase broad_;
    std::unique_ptr<ThreadPool> pool_;
    // The force pass (compute_forces) splits the discs into one index range per thread; a
    // thread owns the disc-disc contacts whose first disc i is in its range and the wall
    // contacts of its discs, and adds them straight into its discs' sums. A contact whose
    // second disc j belongs to a later range ("cross" contact) is computed first into a slot,
    // so that each disc still receives its terms in contact-list order (force_pass.cpp).

    // What the walls' loads and the energy ledger need of a wall contact that touches or
    // dissipates, written by the range that owns it, in list order, into that range's own
    // buffer; the calling thread adds the buffers up in range order after the pass
    // (compute_forces). Contacts with nothing to add leave no record.
    struct WallSum {
        double fx, fy;      // N/m, the force on the disc
        double moment;      // N, cross(contact point, force on the disc), about the origin
        double dissipated;  // J/m, this step
        int32_t wall;       // the wall; -1: not touching (a last dashpot half only)
        int32_t disc;       // the disc's index (in the record's padding: it stays 40 bytes)
    };
    std::vector<std::vector<WallSum>> wall_sums_;  // per range, sized to its wall contacts
    std::vector<size_t> disc_split_, contact_split_, wall_split_;  // per range: first disc, contact, wall contact
    std::vector<int32_t> cross_;            // cross contacts, in list order
    std::vector<size_t> cross_start_;       // per range: its first cross contact in cross_
    std::vector<PairOut> cross_out_;        // their results, same order
    std::vector<int32_t> cross_in_start_, cross_in_;  // per range: the cross contacts whose j it owns (CSR)
    // The cross contacts' own copies of their records and clearances, in cross_in_ order, and
    // each one's place there (cross_pos_[m]): the range that computes them reads and writes
    // only these, never a line of dd_ or clearance_ that the range owning their first disc
    // works on (compute_forces says what that cost). That range copies a changed history
    // back into dd_ when it adds the contact, so dd_ is whole after every pass. Copied from
    // dd_ and clearance_ at the next pass after a cut or an edit of dd_ (cross_copies_stale_:
    // cut_ranges, refresh_dashpots, forget_clearances, which load_state calls). A clearance
    // left behind in clearance_ stays a valid bound (PairSkip), so none is copied back.
    std::vector<DiscContact> cross_dd_;
    std::vector<float> cross_clearance_;
    std::vector<int32_t> cross_pos_;
    std::vector<uint8_t> cross_todo_;  // per cross contact: 1 if this pass gave it results (cross_out_)
    bool cross_copies_stale_ = true;
    int force_ranges_ = 1;
    bool avx2_ = false;                     // def_.simd and the CPU has AVX2
    bool avx512_ = false;                   // and def_.avx512 and the CPU has AVX-512
    std::vector<PairBatch> pair_batch_;     // per range: the AVX2 kernel's results before they are added
    // per material: the stiffness a disc without contacts takes for its step (the law's), N/m
    std::vector<double> default_k_tran_, default_k_rot_;
    void split_force_pass();
    void cut_ranges(size_t r);
    double max_cross_share_ = 0.10;  // of the disc-disc candidates (split_force_pass)
    long one_range_cuts_ = 0;
    double list_seconds_ = 0.0;
    // one range for a busy machine (run_as_one_range_for): steps left, fallbacks, steps run so
    static constexpr long kOneRangeSteps = 4096;
    BusyWatch busy_watch_;
    bool busy_fallback_ = true;
    long one_range_left_ = 0;
    long busy_fallbacks_ = 0;
    long one_range_steps_ = 0;
    double window_pass_seconds_ = 0.0;  // s, the shared passes' wall time in this balancing window
    // passes shared out: their wall time and the ranges' working time, s
    double shared_pass_seconds_ = 0.0, shared_pass_busy_seconds_ = 0.0;
    // The range pass goes block by block, a block being kFuseBlock discs (whole ledger
    // blocks) and the contacts whose first disc is in it; each block is integrated as soon as
    // its pairs and wall contacts are done (compute_forces). Measured on the flume and DB-9k:
    // docs/performance.md.
    static constexpr size_t kFuseBlock = 256;
    struct FuseBlock {
        size_t disc_end;     // its discs end here (they start where the last block ended)
        size_t contact_end;  // its disc-disc contacts end here (dd_ index)
        size_t wall_end;     // its wall contacts end here (dw_ index)
        size_t reach;        // the loads of discs below this are zeroed before its pairs: one
                             // more than the largest disc of the range its pairs add to
    };
    std::vector<FuseBlock> fuse_blocks_;
    std::vector<size_t> fuse_start_;      // per range: its first block (ranges + 1 entries)
    std::vector<size_t> cross_in_reach_;  // per range: the cross contacts into it add below this disc
    // per range: the last force pass whose cross contacts into it are computed (compute_forces)
    struct alignas(64) CrossDone {
        std::atomic<uint64_t> pass{0};
    };
    std::unique_ptr<CrossDone[]> cross_done_;
    // per range, with centred dashpots: the last pass whose discs below cross_in_reach_ are
    // packed (earlier ranges' cross pairs read them), and whose cross pairs' shifts are in
    // cross_shift_ (later ranges add them)
    std::unique_ptr<CrossDone[]> centre_packed_, centre_shifted_;
    size_t cross_done_size_ = 0;
    uint64_t cross_pass_ = 0;
    // measured balance of the ranges (balance_force_pass)
    static constexpr int kBalanceWindow = 64;          // steps between checks
    static constexpr double kBalanceTolerance = 0.03;  // longest range over the mean, - 1
    struct alignas(64) RangeClock {
        double seconds = 0.0;  // s, in the force pass and integration since the last check
        double last = 0.0;     // s, the same in the last pass alone
        long touching_dd = 0;  // touching disc-disc contacts counted by its discs (each pair twice)
        size_t wall_sums = 0;  // records in its wall_sums_ buffer this pass
    };
    // The energy ledger's per-step sums, per block of kLedgerBlock discs: the ranges are cut at
    // block ends, each range sums its blocks (LedgerBlock, integrate_kernel.h), and the blocks
    // are added in order.
    static constexpr size_t kLedgerBlock = 64;
    std::vector<LedgerBlock> ledger_blocks_;
    std::vector<RangeClock> range_clock_;
    std::vector<double> range_share_;  // per range: target share of the work model
    int balance_steps_ = 0;
    long rebalances_ = 0;
    void balance_force_pass();
    void restart_balance_window();
    // the first fault each chunk met in the last pass (reported in index order, so the
    // message does not depend on the thread count)
    struct Fault {
        size_t index = SIZE_MAX;
        std::string message;
    };
    std::vector<Fault> dd_fault_, dw_fault_;
    // What each chunk's integration found in this step (integrate_note), a cache line per
    // chunk: the threads write theirs after every block. (It replaced five vectors whose
    // shared lines both threads wrote; no measurable speed-up,
    // but one record and one reset.)
    struct alignas(64) ChunkNote {
        size_t fault = SIZE_MAX;    // the first disc that left the domain or went non-finite
        double dt_sq = INFINITY;    // s^2, the smallest critical step squared
        double speed = 0.0;         // m/s, the largest |vx| + |vy| (the clearance test's approach)
        double extent = 0.0;        // m, the largest |x| + |y|
        bool escaped = false;       // a disc left its fat box
    };
    std::vector<ChunkNote> chunk_note_;
    // No disc may cross a wall between two steps unseen (integrate_finish, World::step): the
    // automatic step is kept so that the fastest disc moves at most kTravelCap of the
    // smallest radius, and with a fixed step a disc that moved more than kMaxTravel of its
    // radius in one step stops the run. A sound run's discs move far less, so neither changes
    // a bit of one (the flume and DB-9k regressions).
    static constexpr double kMaxTravel = 0.5;
    static constexpr double kTravelCap = 0.25;
    double speed_l1_ = 0.0;        // m/s, the largest |vx| + |vy| after the last step
    double r_min_ = 0.0;           // m, the smallest radius (r_min_stale_: recompute first)
    bool r_min_stale_ = true;
    double smallest_radius();
    double capped_by_travel(double dt);
    void check_travel();
    bool discs_may_have_escaped_ = true;  // false when integrate_discs() saw every disc inside its fat box
    std::vector<DiscContact> dd_, dd_scratch_;
    // The AVX2 pass' clearance test (PairSkip, pair_kernel.h): per disc-disc contact, the
    // approach below which it is known to be open with a zero history (carried with the
    // contact when the lists are rebuilt); the approach since the last reset, m.
    std::vector<float> clearance_, clearance_scratch_;
    double approach_ = 0.0;
    long pairs_skipped_ = 0;  // summed over the steps (the ranges' PairBatch::skipped)
    long candidate_passes_ = 0;
    bool clearances_stale_ = false;  // forget_clearances() was called: reset at the next force pass
    void forget_clearances();
    std::vector<WallContact> dw_, dw_scratch_;
    long touching_dd_ = 0, touching_dw_ = 0;

    // bonds, sorted by (k, l); each one's force on k this step (l gets the opposite) and
    // whether it breaks; per disc its bonds (CSR over bond_disc_, entry 2 b + (disc is l))
    std::vector<Bond> bonds_;
    std::vector<double> bond_inv_rest_;   // 1 / L0 per bond, 1/m (a division per bond and step saved)
    std::vector<uint8_t> bond_chunk_broke_;  // per chunk of the bond pass: some bond breaks this step
    // A bond's terms this step: the force on k (l gets the opposite; zero when it does not
    // act) and its stiffness for the step (zero once broken), so the sums add them without a
    // branch (x + 0 is x for every sum that starts at +0); strain and breaks for the settling.
    struct BondOut {
        double fx, fy, k_tran, strain;
        uint8_t breaks;
    };
    std::vector<BondOut> bond_out_;
    // with BondDef::predict: each bond's dashpot force on k (the predicted force less the
    // spring's) this step and the last, and the energy it took this step (J/m), summed in list
    // order after the pass (bonds.cpp); the last force is history, saved in checkpoints
    std::vector<Vec2> bond_dashpot_, bond_dashpot_last_;
    std::vector<double> bond_dissipated_;
    // constant forces on discs (DiscDef::force), N/m; any_external_force_: some disc has one
    std::vector<Vec2> external_force_;
    bool any_external_force_ = false;
    std::vector<uint32_t> bond_disc_start_, bond_disc_;
    double bond_k0_ = 0.0, bond_k_max_ = 0.0;
    double bond_break_loss_ = 0.0;
    std::vector<BondBreakEvent> bond_breaks_;
    size_t bonds_at_start_ = 0, bonds_lost_ = 0;

    // energy ledger
    double diss_contacts_ = 0, diss_local_ = 0, diss_rotation_ = 0, work_walls_ = 0, removed_walls_ = 0, last_dt_ = 0;
    double kinetic_ = 0;
    // energy()'s partial sums per block (kept between calls: no allocation in the run)
    static constexpr size_t kEnergyBlock = 2048;
    struct EnergyBlock {
        double kinetic_translation = 0, kinetic_rotation = 0, potential = 0, elastic = 0;
    };
    mutable std::vector<EnergyBlock> energy_blocks_;
};

}  // namespace demlab
