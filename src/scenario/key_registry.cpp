#include "scenario/key_registry.h"

#include <cstdio>

#include <algorithm>
#include <cmath>
#include <sstream>

#include "core/error.h"
#include "core/validate.h"

namespace demlab::keys {

std::string where_of(const std::string& file, const toml::node& n, const std::string& key) {
    const auto line = n.source().begin.line;
    return file + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": key '" + key + "'";
}

std::string toml_number(double v) {
    if (std::isinf(v)) return v > 0 ? "inf" : "-inf";
    std::string s = format_number(v);
    if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
    return s;
}

std::string toml_string(const std::string& s) {
    // a basic TOML string on one line: every control character escaped, so a multi-line
    // description or a name with a tab is written back as a scenario that reads again
    std::string out = "\"";
    for (char c : s) {
        const unsigned char u = static_cast<unsigned char>(c);
        switch (c) {
            case '"': out += "\\\""; break;
            case '\\': out += "\\\\"; break;
            case '\n': out += "\\n"; break;
            case '\t': out += "\\t"; break;
            case '\r': out += "\\r"; break;
            case '\b': out += "\\b"; break;
            case '\f': out += "\\f"; break;
            default:
                if (u < 0x20 || u == 0x7f) {
                    char b[8];
                    std::snprintf(b, sizeof b, "\\u%04X", unsigned(u));
                    out += b;
                } else {
                    out += c;
                }
        }
    }
    return out + "\"";
}

std::string node_text(const toml::node& n) {
    std::ostringstream o;
    if (auto v = n.as_string()) return toml_string(v->get());
    n.visit([&](auto&& x) { o << x; });
    return o.str();
}

double read_number(const toml::node& n, const std::string& where, const std::string& unit) {
    if (auto v = n.value<double>(); v && (n.is_floating_point() || n.is_integer())) return *v;
    throw InputError(where + " = " + node_text(n) + ": must be a number (" + unit + ")");
}

Vec2 read_vec2(const toml::node& n, const std::string& where, const std::string& unit) {
    const toml::array* a = n.as_array();
    if (!a || a->size() != 2) throw InputError(where + " = " + node_text(n) + ": must be [x, y] (" + unit + ")");
    Vec2 v(read_number(*a->get(0), where, unit), read_number(*a->get(1), where, unit));
    if (!std::isfinite(v.x()) || !std::isfinite(v.y())) throw InputError(where + ": must be finite (" + unit + ")");
    return v;
}

namespace {

using DRef = std::function<double&(Scenario&)>;
using IRef = int& (*)(Scenario&);
using BRef = bool& (*)(Scenario&);
using SRef = std::string& (*)(Scenario&);
using VRef = Vec2& (*)(Scenario&);

// a real number in [lo, hi] (open ends when lo_open / hi_open)
Key real(std::string name, std::string unit, std::string doc, DRef ref, double lo, double hi, bool lo_open = false,
         bool hi_open = false) {
    std::ostringstream acc;
    acc << (lo_open ? "(" : "[") << toml_number(lo) << ", " << toml_number(hi) << (hi_open ? ")" : "]");
    Key k{name, unit, acc.str(), std::move(doc), nullptr, nullptr};
    const std::string accepted = k.accepted;
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        const double v = read_number(n, where, unit);
        const bool ok = !std::isnan(v) && (lo_open ? v > lo : v >= lo) && (hi_open ? v < hi : v <= hi);
        if (!ok) throw InputError(where + " = " + format_number(v) + " " + unit + ": must be in " + accepted);
        ref(s) = v;
    };
    k.get = [=](const Scenario& s) { return toml_number(ref(const_cast<Scenario&>(s))); };
    return k;
}

Key integer(std::string name, std::string unit, std::string doc, IRef ref, long lo, long hi) {
    Key k{name, unit, "integer in [" + std::to_string(lo) + ", " + std::to_string(hi) + "]", std::move(doc), nullptr,
          nullptr};
    const std::string accepted = k.accepted;
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<int64_t>();
        if (!v) throw InputError(where + " = " + node_text(n) + ": must be an " + accepted);
        if (*v < lo || *v > hi) throw InputError(where + " = " + std::to_string(*v) + ": must be an " + accepted);
        ref(s) = int(*v);
    };
    k.get = [=](const Scenario& s) { return std::to_string(ref(const_cast<Scenario&>(s))); };
    return k;
}

Key boolean(std::string name, std::string doc, BRef ref) {
    Key k{name, "-", "true or false", std::move(doc), nullptr, nullptr};
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<bool>();
        if (!v) throw InputError(where + " = " + node_text(n) + ": must be true or false");
        ref(s) = *v;
    };
    k.get = [=](const Scenario& s) { return std::string(ref(const_cast<Scenario&>(s)) ? "true" : "false"); };
    return k;
}

Key text(std::string name, std::string doc, SRef ref, std::vector<std::string> choices = {}) {
    std::string acc = "any text";
    if (!choices.empty()) {
        acc = "one of";
        for (auto& c : choices) acc += " \"" + c + "\"";
    }
    Key k{name, "-", acc, std::move(doc), nullptr, nullptr};
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        auto v = n.value_exact<std::string>();
        if (!v) throw InputError(where + " = " + node_text(n) + ": must be a string (" + acc + ")");
        if (!choices.empty() && std::find(choices.begin(), choices.end(), *v) == choices.end())
            throw InputError(where + " = \"" + *v + "\": must be " + acc);
        ref(s) = *v;
    };
    k.get = [=](const Scenario& s) { return toml_string(ref(const_cast<Scenario&>(s))); };
    return k;
}

// [x, y], finite; with a max_norm > 0, its magnitude at most that
Key vec2(std::string name, std::string unit, std::string doc, VRef ref, double max_norm = 0.0) {
    Key k{name, unit, max_norm > 0.0 ? "[x, y], magnitude <= " + format_number(max_norm) : "[x, y], finite", std::move(doc),
          nullptr, nullptr};
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        const Vec2 v = read_vec2(n, where, unit);
        if (max_norm > 0.0 && !(v.norm() <= max_norm))
            throw InputError(where + " = [" + format_number(v.x()) + ", " + format_number(v.y()) + "] " + unit +
                             ": its magnitude must be at most " + format_number(max_norm) + " " + unit);
        ref(s) = v;
    };
    k.get = [=](const Scenario& s) {
        const Vec2& v = ref(const_cast<Scenario&>(s));
        return "[" + toml_number(v.x()) + ", " + toml_number(v.y()) + "]";
    };
    return k;
}

// enum-valued keys stored in non-string fields
template <typename E>
Key choice(std::string name, std::string doc, std::function<E&(Scenario&)> ref, std::vector<std::pair<std::string, E>> map) {
    std::string acc = "one of";
    for (auto& [t, e] : map) acc += " \"" + t + "\"";
    Key k{name, "-", acc, std::move(doc), nullptr, nullptr};
    k.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        std::string v;
        if (auto str = n.value_exact<std::string>()) v = *str;
        else if (auto i = n.value_exact<int64_t>()) v = std::to_string(*i);
        else throw InputError(where + " = " + node_text(n) + ": must be " + acc);
        for (auto& [t, e] : map)
            if (t == v) {
                ref(s) = e;
                return;
            }
        throw InputError(where + " = \"" + v + "\": must be " + acc);
    };
    k.get = [=](const Scenario& s) {
        for (auto& [t, e] : map)
            if (e == ref(const_cast<Scenario&>(s))) return toml_string(t);
        return std::string("\"?\"");
    };
    return k;
}

Key polygon(std::string name, std::string accepted, std::string doc, std::vector<Vec2>& (*ref)(Scenario&));  // below

// A law's keys (law_part.h: Law::keys), named [kSection].name, its Def's fields in WorldDef::laws.
template <typename Law>
struct LawKeys {
    std::vector<Key>& k;
    using Def = typename Law::Def;
    static std::string key(const char* name) { return std::string(Law::kSection) + "." + name; }
    void real(const char* name, const char* unit, const char* doc, double Def::*field, double lo, double hi, bool lo_open = false,
              bool hi_open = false) {
        k.push_back(keys::real(key(name), unit, doc, [field](Scenario& s) -> double& { return s.world.law_def<Law>().*field; }, lo,
                               hi, lo_open, hi_open));
    }
    template <typename E>
    void choice(const char* name, const char* doc, E Def::*field, std::vector<std::pair<std::string, E>> map) {
        k.push_back(keys::choice<E>(key(name), doc, [field](Scenario& s) -> E& { return s.world.law_def<Law>().*field; }, std::move(map)));
    }
};


void add_scenario_and_material_keys(std::vector<Key>& k) {
    // scenario
    k.push_back(text("scenario.name", "name of the scenario, used in outputs and as the default run folder runs/<name>: a plain name (no '/', '\\', '..' or control character, not starting with '.')", [](Scenario& s) -> std::string& { return s.name; }));
    k.push_back(text("scenario.description", "free text", [](Scenario& s) -> std::string& { return s.description; }));
    k.push_back(text("scenario.solver", "dem: the discs (the thesis' PFC2D model); dan: the depth-averaged continuum model on a flume's path ([dan], docs/dan.md); dem3: spheres with the DEBRIS law on a 3-D terrain ([dem3], docs/debris.md)", [](Scenario& s) -> std::string& { return s.solver; }, {"dem", "dan", "dem3"}));
    {
        Key seed{"scenario.seed", "-", "integer in [0, 2^63)", "seed of every random draw (release mass radii and positions)", nullptr, nullptr};
        seed.set = [](Scenario& s, const toml::node& n, const std::string& where) {
            auto v = n.value_exact<int64_t>();
            if (!v || *v < 0) throw InputError(where + " = " + node_text(n) + ": must be an integer in [0, 2^63 - 1]");
            s.seed = static_cast<unsigned long long>(*v);
        };
        seed.get = [](const Scenario& s) { return std::to_string(s.seed); };
        k.push_back(seed);
    }
    // material
    k.push_back(real("material.density", "kg/m3", "disc density (Table 15: quartz sand)", [](Scenario& s) -> double& { return s.disc.density; }, 0, 1e6, true));
    k.push_back(real("material.kn", "N/m", "disc normal stiffness, in series with the partner's (Table 15: 1e8)", [](Scenario& s) -> double& { return s.disc.kn; }, 0, 1e15, true));
    k.push_back(real("material.ks", "N/m", "disc shear stiffness (Table 15: 1e8)", [](Scenario& s) -> double& { return s.disc.ks; }, 0, 1e15, true));
    k.push_back(real("material.friction_disc_deg", "deg", "disc-disc friction angle (calibrated on the dam break: 15.5)", [](Scenario& s) -> double& { return s.disc_friction_deg; }, 0, 89));
    k.push_back(real("material.friction_wall_deg", "deg", "disc-wall friction angle (basal angle on the zinc-coated sheet: 21.7)", [](Scenario& s) -> double& { return s.wall_friction_deg; }, 0, 89));
    k.push_back(real("material.wall_kn", "N/m", "wall normal stiffness (same as discs unless set)", [](Scenario& s) -> double& { return s.wall.kn; }, 0, 1e15, true));
    k.push_back(real("material.wall_ks", "N/m", "wall shear stiffness", [](Scenario& s) -> double& { return s.wall.ks; }, 0, 1e15, true));
    k.push_back(choice<FrictionRule>("material.friction_rule_disc_disc", "which coefficient a disc-disc contact takes (PFC: min)", [](Scenario& s) -> FrictionRule& { return s.world.friction_rule_disc_disc; }, {{"min", FrictionRule::Min}, {"max", FrictionRule::Max}}));
    k.push_back(choice<FrictionRule>("material.friction_rule_disc_wall", "which coefficient a disc-wall contact takes (thesis 4.3.2: max)", [](Scenario& s) -> FrictionRule& { return s.world.friction_rule_disc_wall; }, {{"min", FrictionRule::Min}, {"max", FrictionRule::Max}}));
}

void add_dynamics_keys(std::vector<Key>& k) {
    // damping
    k.push_back(real("damping.beta_n", "-", "normal critical damping ratio (Table 15: 0.5)", [](Scenario& s) -> double& { return s.world.damping.beta_n; }, 0, 1, false, true));
    k.push_back(real("damping.beta_s", "-", "shear critical damping ratio (Table 15: 0.5)", [](Scenario& s) -> double& { return s.world.damping.beta_s; }, 0, 1, false, true));
    k.push_back(real("damping.local_alpha", "-", "PFC local damping (eq. 2.51) during the flow, 0: none (the thesis' flow runs use the viscous dashpots only; the release's settling sets its own, release.settle_alpha)", [](Scenario& s) -> double& { return s.world.damping.local_alpha; }, 0, 1, false, true));
    k.push_back(choice<DashpotMode>("damping.dp_mode", "PFC dashpot mode: 0 both always; 1 no tensile normal force; 2 no shear dashpot while sliding; 3 both", [](Scenario& s) -> DashpotMode& { return s.world.damping.dp_mode; }, {{"0", DashpotMode::Full}, {"1", DashpotMode::NoTension}, {"2", DashpotMode::NoShearWhileSliding}, {"3", DashpotMode::NoTensionNoShearWhileSliding}}));
    // rotation
    k.push_back(integer("rotation.model", "-", "1: rotation locked; 2: free rotation with Preh-Poisel rolling resistance at walls; 3: 2 plus rotational damping at disc-disc contacts", [](Scenario& s) -> int& { return s.world.rotation.model; }, 1, 3));
    k.push_back(real("rotation.u_rr", "m", "penetration depth of the rolling resistance, models 2 and 3 (Table 15: 0.00015); < 0.6 r_min", [](Scenario& s) -> double& { return s.world.rotation.u_rr; }, 0, 1));
    k.push_back(choice<RollingForm>("rotation.rolling_form", "g in eq. 2.71: gravity (literal) or the actual wall normal force per mass", [](Scenario& s) -> RollingForm& { return s.world.rotation.rolling_form; }, {{"literal", RollingForm::Literal}, {"normal_force", RollingForm::NormalForce}}));
    k.push_back(real("rotation.mu_br", "-", "rotational damping factor per step at disc-disc contacts, model 3 (Table 15: 0.5)", [](Scenario& s) -> double& { return s.world.rotation.mu_br; }, 0, 1, true, false));
    k.push_back(choice<RotDampingPer>("rotation.damping_per", "mu_Br once per disc touching discs, or once per contact", [](Scenario& s) -> RotDampingPer& { return s.world.rotation.damping_per; }, {{"disc", RotDampingPer::Disc}, {"contact", RotDampingPer::Contact}}));
    // time step
    k.push_back(boolean("timestep.automatic", "PFC's automatic step (docs/engine.md) or the fixed one", [](Scenario& s) -> bool& { return s.world.timestep.automatic; }));
    k.push_back(real("timestep.safety", "-", "safety factor of the automatic step (PFC: 0.8)", [](Scenario& s) -> double& { return s.world.timestep.safety; }, 0, 1, true, false));
    k.push_back(real("timestep.fixed", "s", "the step when automatic = false", [](Scenario& s) -> double& { return s.world.timestep.fixed; }, 0, 1, true));
    k.push_back(choice<DashpotScheme>("timestep.dashpots", "how the dashpots are integrated (docs/engine.md, \"Dashpots\"): centred (at the step's centre, implicit per contact: stable at PFC's rule as printed) or lagged (from the velocities half a step back, the scheme of earlier builds: with timestep.damping_correction it reproduces their results bit for bit)", [](Scenario& s) -> DashpotScheme& { return s.world.timestep.dashpots; }, {{"centred", DashpotScheme::Centred}, {"lagged", DashpotScheme::Lagged}}));
    k.push_back(boolean("timestep.damping_correction", "shrink the step's bounds for local damping and, with lagged dashpots, for the dashpots (stability, docs/engine.md)", [](Scenario& s) -> bool& { return s.world.timestep.damping_correction; }));
    // world
    k.push_back(vec2("world.gravity", "m/s2", "gravity vector (its magnitude at most 1e3 m/s2, about a hundred g)", [](Scenario& s) -> Vec2& { return s.world.gravity; }, 1e3));
    k.push_back(real("world.broadphase_margin", "m", "smallest pad of the broad phase's fat boxes (moving discs get wider ones); 0 = half the smallest radius", [](Scenario& s) -> double& { return s.world.broadphase_margin; }, 0, 1));
    k.push_back(real("world.joint_tolerance", "m", "wall ends closer than this are joined", [](Scenario& s) -> double& { return s.world.joint_tolerance; }, 0, 0.1));
    k.push_back(polygon("world.domain", "[] or 2 points [[x_lo, y_lo], [x_hi, y_hi]], x_lo < x_hi, y_lo < y_hi, holding every disc at t = 0", "the domain's box: a disc whose centre leaves it is lost (world.lost_discs); [] = the box of the walls, the discs and the set-up padded by 0.5 m (give it where there are no walls to bound the flight)", [](Scenario& s) -> std::vector<Vec2>& { return s.domain; }));
    k.push_back(choice<LostDiscs>("world.lost_discs", "a disc whose centre leaves the domain (world.domain; by default the walls' box padded by 0.5 m: over a wall's free end, off a profile's end): remove (taken out, recorded in lost.csv, its energy booked in the ledger) or stop (the run ends with exit 3)", [](Scenario& s) -> LostDiscs& { return s.world.lost_discs; }, {{"remove", LostDiscs::Remove}, {"stop", LostDiscs::Stop}}));
    k.push_back(real("world.max_overlap_ratio", "-", "an overlap beyond this fraction of the smaller radius stops the run (blow-up)", [](Scenario& s) -> double& { return s.world.max_overlap_ratio; }, 0, 2, true));
    k.push_back(choice<SpaceOrder>("world.space_order", "renumber the discs in space order every world.space_order_steps steps as they flow, so that a contact's two discs stay near in memory (docs/performance.md): on, off, or auto (on above 20,000 discs: geometry A at scales 2 and 1). Not with bonds (auto leaves a bonded world as it is). The same physics in another order of the sums: other bits, the same on any thread count", [](Scenario& s) -> SpaceOrder& { return s.world.space_order; }, {{"auto", SpaceOrder::Auto}, {"on", SpaceOrder::On}, {"off", SpaceOrder::Off}}));
    k.push_back(integer("world.space_order_steps", "-", "steps between two renumberings in space order (world.space_order)", [](Scenario& s) -> int& { return s.world.space_order_steps; }, 1, 1000000000));
    // contact.law names every registered law; each law adds its own section's keys (law_part.h)
    {
        std::vector<std::pair<std::string, ContactLawKind>> laws;
        std::vector<std::string> texts;
        for_each_contact_law([&](auto law) {
            using Law = decltype(law);
            laws.emplace_back(Law::kName, law_kind<Law>());
            texts.push_back(std::string(Law::kName) + " (" + Law::kSummary + ")");
        });
        std::string doc = "the contact law of every contact: ";
        for (size_t n = 0; n < texts.size(); ++n) doc += (n == 0 ? "" : n + 1 == texts.size() ? " or " : ", ") + texts[n];
        k.push_back(choice<ContactLawKind>("contact.law", doc, [](Scenario& s) -> ContactLawKind& { return s.world.law; }, laws));
    }
    for_each_contact_law([&](auto law) {
        LawKeys<decltype(law)> add{k};
        decltype(law)::keys(add);
    });
}

// An array of points [[x, y], ...] (m).
Key polygon(std::string name, std::string accepted, std::string doc, std::vector<Vec2>& (*ref)(Scenario&)) {
    Key key{name, "m", std::move(accepted), std::move(doc), nullptr, nullptr};
    key.set = [=](Scenario& s, const toml::node& n, const std::string& where) {
        const toml::array* a = n.as_array();
        if (!a) throw InputError(where + " = " + node_text(n) + ": must be an array of points [x, y] (m)");
        std::vector<Vec2>& v = ref(s);
        v.clear();
        for (const auto& e : *a) v.push_back(read_vec2(e, where, "m"));
    };
    key.get = [=](const Scenario& s) {
        const std::vector<Vec2>& v = ref(const_cast<Scenario&>(s));
        std::string out = "[";
        for (size_t i = 0; i < v.size(); ++i) out += (i ? ", [" : "[") + toml_number(v[i].x()) + ", " + toml_number(v[i].y()) + "]";
        return out + "]";
    };
    return key;
}

void add_cohesion_keys(std::vector<Key>& k) {
    // cohesion (docs/spec/COHESION.md section 3; AvaFrame's names in brackets)
    k.push_back(boolean("cohesion.enabled", "elastic bonds that break between neighbouring discs (or spheres with scenario.solver = \"dem3\"), built at t = 0 of the run [snowSlide]", [](Scenario& s) -> bool& { return s.cohesion.enabled; }));
    k.push_back(real("cohesion.modulus", "Pa", "bond modulus E: a bond pulls with eps E A, A = t L / sqrt(3) [cohesiveSurfaceTension]; the network's plane modulus is 2E/3 (spheres: A = L0 L / (2 sqrt 2), the close-packed network's modulus E/3 along a cube axis)", [](Scenario& s) -> double& { return s.cohesion.bond.modulus; }, 0, 1e12, true));
    k.push_back(real("cohesion.max_strain", "-", "a bond strained beyond this breaks for good [cohesionMaxStrain]", [](Scenario& s) -> double& { return s.cohesion.bond.max_strain; }, 0, 0.5, true));
    k.push_back(real("cohesion.min_distance", "m", "a bond this short or shorter is skipped for the step: no force, no break [minDistCohesion]", [](Scenario& s) -> double& { return s.cohesion.bond.min_distance; }, 0, 1));
    k.push_back(choice<BondArea>("cohesion.area", "the bond's face A = t L/sqrt(3) with the current length L (AvaFrame) or the rest length (a linear spring)", [](Scenario& s) -> BondArea& { return s.cohesion.bond.area; }, {{"current", BondArea::Current}, {"rest", BondArea::Rest}}));
    k.push_back(choice<BondBreak>("cohesion.break_mode", "bonds break past max_strain in tension and compression (AvaFrame), or in tension only", [](Scenario& s) -> BondBreak& { return s.cohesion.bond.break_mode; }, {{"both", BondBreak::Both}, {"tension", BondBreak::Tension}}));
    k.push_back(boolean("cohesion.predict", "AvaFrame's bond lengths from positions predicted one step, x + dt v (C5): adds a dashpot c = k_b dt to every bond, damping ratio omega dt / 2 (C11), booked as dissipation", [](Scenario& s) -> bool& { return s.cohesion.bond.predict; }));
    k.push_back(choice<BondFilter>("cohesion.filter", "which Delaunay triangles give bonds (spheres: which edges of the 3-D triangulation): triangular (longest side <= max_edge_factor times the shortest such), length (<= max_bond_length), gap (every side's gap <= max_gap), none", [](Scenario& s) -> BondFilter& { return s.cohesion.build.filter; }, {{"triangular", BondFilter::Triangular}, {"length", BondFilter::Length}, {"gap", BondFilter::Gap}, {"none", BondFilter::None}}));
    k.push_back(real("cohesion.max_edge_factor", "-", "filter triangular: AvaFrame's 1.1", [](Scenario& s) -> double& { return s.cohesion.build.max_edge_factor; }, 1.0, 3.0));
    k.push_back(real("cohesion.max_bond_length", "m", "filter length: the longest side a kept triangle may have; 0 is refused with that filter", [](Scenario& s) -> double& { return s.cohesion.build.max_bond_length; }, 0, 100));
    k.push_back(real("cohesion.max_gap", "m", "filter gap: the largest gap L - r_k - r_l of a kept triangle's sides; 0 = 0.25 r_min", [](Scenario& s) -> double& { return s.cohesion.build.max_gap; }, 0, 10));
    {
        Key bonds{"cohesion.bonds", "-", "array of [k, l], k != l, ids of discs", "explicit bonds (tests); when given, no triangulation", nullptr, nullptr};
        bonds.set = [](Scenario& s, const toml::node& n, const std::string& where) {
            const toml::array* a = n.as_array();
            if (!a) throw InputError(where + " = " + node_text(n) + ": must be an array of disc-id pairs, e.g. [[0, 1], [1, 2]]");
            s.cohesion.bonds.clear();
            for (const auto& e : *a) {
                const toml::array* p = e.as_array();
                auto k0 = p && p->size() == 2 ? (*p)[0].value_exact<int64_t>() : std::nullopt;
                auto k1 = p && p->size() == 2 ? (*p)[1].value_exact<int64_t>() : std::nullopt;
                if (!k0 || !k1 || *k0 < 0 || *k1 < 0)
                    throw InputError(where + ": entry " + node_text(e) + " must be a pair [k, l] of disc ids >= 0");
                if (*k0 == *k1) throw InputError(where + ": entry " + node_text(e) + ": a bond joins two different discs");
                s.cohesion.bonds.emplace_back(long(*k0), long(*k1));
            }
        };
        bonds.get = [](const Scenario& s) {
            std::string out = "[";
            for (size_t i = 0; i < s.cohesion.bonds.size(); ++i)
                out += (i ? ", [" : "[") + std::to_string(s.cohesion.bonds[i].first) + ", " + std::to_string(s.cohesion.bonds[i].second) + "]";
            return out + "]";
        };
        k.push_back(bonds);
    }
    // lattice release (COHESION.md section 3)
    k.push_back(polygon("lattice_release.region", "array of >= 3 points [x, y], a simple polygon", "the polygon the lattice's discs fill (a centre inside it and at least r from every wall makes a disc)", [](Scenario& s) -> std::vector<Vec2>& { return s.lattice_release.region; }));
    k.push_back(text("lattice_release.top", "CSV file of the initial mass's top surface, rows x,y in m with x increasing (as terrain.profile; a relative path is taken from the scenario file's folder): the lattice fills the area between it and the terrain's profile, over its x range; instead of lattice_release.region", [](Scenario& s) -> std::string& { return s.lattice_release.top; }));
    k.push_back(vec2("lattice_release.origin", "m", "a node of the lattice (required)", [](Scenario& s) -> Vec2& { return s.lattice_release.origin; }));
    k.push_back(real("lattice_release.angle_deg", "deg", "direction of the rows, counter-clockwise from +x", [](Scenario& s) -> double& { return s.lattice_release.angle_deg; }, -180, 180));
    k.push_back(real("lattice_release.spacing", "m", "distance between neighbouring nodes; 0 = 2 r_max", [](Scenario& s) -> double& { return s.lattice_release.spacing; }, 0, 100));
    k.push_back(real("lattice_release.r_min", "m", "smallest radius (required, > 0)", [](Scenario& s) -> double& { return s.lattice_release.r_min; }, 0, 10));
    k.push_back(real("lattice_release.r_max", "m", "largest radius; 0 = r_min (radii uniform in [r_min, r_max] from scenario.seed)", [](Scenario& s) -> double& { return s.lattice_release.r_max; }, 0, 10));
    k.push_back(boolean("lattice_release.settle", "settle the lattice under gravity before t = 0, against every wall (one removed at t = 0 holds it as a gate), with local damping lattice_release.settle_alpha until release.settle_ratio, at most release.settle_max_time; the bonds are built from the settled positions", [](Scenario& s) -> bool& { return s.lattice_release.settle; }));
    k.push_back(real("lattice_release.settle_alpha", "-", "local damping while the lattice settles (lattice_release.settle; with friction, rotation locked)", [](Scenario& s) -> double& { return s.lattice_release.settle_alpha; }, 0, 1, false, true));
}

void add_setups_keys(std::vector<Key>& k) {
    // flume
    k.push_back(vec2("flume.w1_start", "m", "slope W1, upper end (Table 2)", [](Scenario& s) -> Vec2& { return s.flume.w1_p0; }));
    k.push_back(vec2("flume.w1_end", "m", "slope W1, lower end", [](Scenario& s) -> Vec2& { return s.flume.w1_p1; }));
    k.push_back(vec2("flume.arc_centre", "m", "transition arc W2, centre", [](Scenario& s) -> Vec2& { return s.flume.arc_centre; }));
    k.push_back(real("flume.arc_radius", "m", "transition arc W2, radius", [](Scenario& s) -> double& { return s.flume.arc_radius; }, 0, 100, true));
    k.push_back(real("flume.arc_start_deg", "deg", "transition arc W2, start angle (counter-clockwise from +x)", [](Scenario& s) -> double& { return s.flume.arc_start_deg; }, -360, 720));
    k.push_back(real("flume.arc_end_deg", "deg", "transition arc W2, end angle", [](Scenario& s) -> double& { return s.flume.arc_end_deg; }, -360, 720));
    k.push_back(vec2("flume.w3_start", "m", "barrier W3, lower end", [](Scenario& s) -> Vec2& { return s.flume.w3_p0; }));
    k.push_back(vec2("flume.w3_end", "m", "barrier W3, upper end", [](Scenario& s) -> Vec2& { return s.flume.w3_p1; }));
    k.push_back(vec2("flume.gate_start", "m", "gate W4, lower end (on W1) (Table 3)", [](Scenario& s) -> Vec2& { return s.flume.gate_p0; }));
    k.push_back(vec2("flume.gate_end", "m", "gate W4, upper end", [](Scenario& s) -> Vec2& { return s.flume.gate_p1; }));
    k.push_back(vec2("flume.lid_start", "m", "lid W5, end at the gate", [](Scenario& s) -> Vec2& { return s.flume.lid_p0; }));
    k.push_back(vec2("flume.lid_end", "m", "lid W5, end at W1's upper end", [](Scenario& s) -> Vec2& { return s.flume.lid_p1; }));
    // dam break
    k.push_back(real("dam_break.width", "m", "column width: back wall at x = 0, gate at x = width (scenarios/dam-break.toml: 0.30, identified from the thesis' PFC2D angles; the earlier assumption 0.20)", [](Scenario& s) -> double& { return s.dam_break.width; }, 0, 10, true));
    k.push_back(real("dam_break.height", "m", "column height (scenarios/dam-break.toml: 0.2667; 0.08 m2 holds the thesis' 9,439 discs; the earlier assumption 0.40)", [](Scenario& s) -> double& { return s.dam_break.height; }, 0, 10, true));
    k.push_back(real("dam_break.sections_start", "m", "where the five 10 cm sections of the deposit's surface begin, from the back wall: section 5 (gamma_5) spans [start, start + 0.1], section 1 [start + 0.4, start + 0.5]; gamma_ges runs from the surface at start to the toe (0: at the back wall; scenarios/dam-break.toml: 0.10, identified from the thesis' PFC2D angles; data/dam_break_geometry.md)", [](Scenario& s) -> double& { return s.dam_break.sections_start; }, 0, 10, false));
    k.push_back(real("dam_break.floor_length", "m", "length of the floor from the back wall", [](Scenario& s) -> double& { return s.dam_break.floor_length; }, 0, 100, true));
    // terrain
    k.push_back(text("terrain.profile", "CSV file of the ground's profile (a relative path is taken from the scenario file's folder): rows x,y in m with x increasing (a header line and # comments allowed); a wall per segment, the ground below, friction and stiffness from material.friction_wall_deg, wall_kn, wall_ks", [](Scenario& s) -> std::string& { return s.terrain.profile; }));
    k.push_back(text("terrain.grid", "an ESRI ASCII grid (.asc: ncols, nrows, xllcorner/xllcenter, yllcorner/yllcenter, cellsize, NODATA_value, then the rows, northernmost first) sampled bilinearly along terrain.section into the profile (distance along the section as x); instead of terrain.profile; a relative path is taken from the scenario file's folder", [](Scenario& s) -> std::string& { return s.terrain.grid; }));
    k.push_back(polygon("terrain.section", "2 points [x, y] in the grid's coordinates", "the section line through terrain.grid, from its first point (x = 0 of the profile) to its second", [](Scenario& s) -> std::vector<Vec2>& { return s.terrain.section; }));
    k.push_back(real("terrain.spacing", "m", "distance between the section's samples of terrain.grid; 0 = the grid's cell size", [](Scenario& s) -> double& { return s.terrain.spacing; }, 0, 1e4));
    k.push_back(polygon("terrain.barrier", "array of >= 2 points [x, y], the first on the profile (within 1 mm), x never decreasing", "a barrier (a dam) on the profile: a polyline from its foot, the flow on its left (up the upstream face first), a wall per segment as the profile's; its load goes to forces.csv's barrier columns, the bed path runs up its face (run-up, arrival); [] = none", [](Scenario& s) -> std::vector<Vec2>& { return s.terrain.barrier; }));
    k.push_back(polygon("terrain.release", "array of >= 3 points [x, y] of a convex polygon", "the polygon the release mass fills (generated as for the flume, then dropped onto the profile); its top (the edge facing most upwards) is taken away for the last settling phase, so the mass must not pour out over a lower side; [] = the [[discs]] given", [](Scenario& s) -> std::vector<Vec2>& { return s.terrain.release; }));
}

// The continuum model (docs/spec/DAN.md section 3; its equations D1-D15 in brackets)
void add_dan_keys(std::vector<Key>& k) {
    k.push_back(integer("dan.blocks", "-", "boundary blocks n (n - 1 mass blocks between them)", [](Scenario& s) -> int& { return s.dan.blocks; }, 3, 100000));
    k.push_back(choice<DanColumns>("dan.columns", "mass blocks as vertical columns (Mancarella & Hungr 2010) or normal to the bed [D1]", [](Scenario& s) -> DanColumns& { return s.dan.columns; }, {{"vertical", DanColumns::Vertical}, {"normal", DanColumns::Normal}}));
    k.push_back(real("dan.density", "kg/m3", "bulk density of the flow (lab: 1630); only the forces scale with it", [](Scenario& s) -> double& { return s.dan.density; }, 0, 1e5, true));
    k.push_back(real("dan.width", "m", "width B (1 m as PFC2D: results per metre)", [](Scenario& s) -> double& { return s.dan.width; }, 0, 100, true));
    k.push_back(real("dan.phi_internal_deg", "deg", "dynamic internal friction angle (Table 16: 30.9) [D5]", [](Scenario& s) -> double& { return s.dan.phi_internal_deg; }, 0, 89));
    k.push_back(real("dan.phi_basal_deg", "deg", "basal friction angle (Table 16: 21.7) [D10]", [](Scenario& s) -> double& { return s.dan.phi_basal_deg; }, 0, 89));
    k.push_back(real("dan.pore_pressure_ratio", "-", "pore-pressure ratio r_u [D10]", [](Scenario& s) -> double& { return s.dan.pore_pressure_ratio; }, 0, 1, false, true));
    k.push_back(choice<DanKMode>("dan.k_mode", "earth-pressure coefficient from the blocks' strains between active and passive (dan), or k_fixed [D6]", [](Scenario& s) -> DanKMode& { return s.dan.k_mode; }, {{"dan", DanKMode::Dan}, {"fixed", DanKMode::Fixed}}));
    k.push_back(real("dan.k_fixed", "-", "k with k_mode fixed (1: a fluid)", [](Scenario& s) -> double& { return s.dan.k_fixed; }, 0, 100));
    k.push_back(real("dan.k_initial", "-", "k at t = 0, clamped at the first update", [](Scenario& s) -> double& { return s.dan.k_initial; }, 0, 100));
    k.push_back(real("dan.k_stiffness", "-", "E_k: k changes by -E_k times the strain increment; 0 = the Savage-Hutter switch [D6]", [](Scenario& s) -> double& { return s.dan.k_stiffness; }, 0, 1e9));
    k.push_back(real("dan.lambda", "-", "Hungr's factor of the modified basal angle (eq. 2.38) [D4]", [](Scenario& s) -> double& { return s.dan.lambda; }, -1, 1));
    k.push_back(real("dan.slope_window", "-", "the length, in flow depths h of the block, over which the modified basal angle reads the free surface's slope, centred on the block and never shorter than it: the surface at the scale of the flow's depth, which refinement does not change; 0 = the block's own slope (eq. 2.38 literally) [D4]", [](Scenario& s) -> double& { return s.dan.slope_window; }, 0, 10));
    k.push_back(choice<DanPressure>("dan.pressure_form", "DAN's k dH/ds at the boundary blocks, or the conservative difference of the blocks' thrusts [D7]", [](Scenario& s) -> DanPressure& { return s.dan.pressure_form; }, {{"dan", DanPressure::Dan}, {"conservative", DanPressure::Conservative}}));
    k.push_back(choice<DanEndHeight>("dan.end_height", "the surface at the end blocks: half the end block's height (literal) or zero (it meets the bed) [D7, D8]", [](Scenario& s) -> DanEndHeight& { return s.dan.end_height; }, {{"half", DanEndHeight::Half}, {"zero", DanEndHeight::Zero}}));
    k.push_back(boolean("dan.pressure_centripetal", "also scale the pressure by (1 + kappa v^2 / (g cos alpha)), as AvaFrame does", [](Scenario& s) -> bool& { return s.dan.pressure_centripetal; }));
    k.push_back(boolean("dan.centripetal", "the centripetal term kappa v^2 in the basal resistance [D10]", [](Scenario& s) -> bool& { return s.dan.centripetal; }));
    k.push_back(real("dan.curvature_window", "m", "running mean of the path's curvature over this length; 0 = none", [](Scenario& s) -> double& { return s.dan.curvature_window; }, 0, 1));
    k.push_back(boolean("dan.smoothing", "the thesis' velocity smoothing (section 2.2.6) [D12]", [](Scenario& s) -> bool& { return s.dan.smoothing; }));
    k.push_back(real("dan.cs_interior", "-", "smoothing factor c_s of the inner boundary blocks (thesis: 0.02)", [](Scenario& s) -> double& { return s.dan.cs_interior; }, 0, 1));
    k.push_back(real("dan.cs_ends", "-", "smoothing factor c_s of the front and tail blocks (thesis: 0.004)", [](Scenario& s) -> double& { return s.dan.cs_ends; }, 0, 1));
    k.push_back(choice<DanSpacing>("dan.smoothing_spacing", "the smoothing's spacings along x (thesis) or along the path [D12]", [](Scenario& s) -> DanSpacing& { return s.dan.smoothing_spacing; }, {{"horizontal", DanSpacing::Horizontal}, {"path", DanSpacing::Path}}));
    k.push_back(real("dan.smoothing_dt_ref", "s", "the smoothing acts as c_s dt / smoothing_dt_ref a step, so its effect per second is independent of dt; 0 = c_s a step, literally", [](Scenario& s) -> double& { return s.dan.smoothing_dt_ref; }, 0, 1));
    k.push_back(choice<DanMomentum>("dan.momentum_correction", "give the moving blocks back the momentum the smoothing moved (global), or not (none) [D13]", [](Scenario& s) -> DanMomentum& { return s.dan.momentum_correction; }, {{"global", DanMomentum::Global}, {"none", DanMomentum::None}}));
    k.push_back(real("dan.shock_viscosity", "-", "c_quad of the bore's dissipation: a compressed mass block (v_(j+1) < v_j) pushes its boundary blocks apart with the thrust rho B h (c_quad dv^2 + c_lin sqrt(k g h cos alpha) |dv|), so the arriving flow's energy is lost in the bore at the deposit, over a few blocks whatever their number; 0 = none [D16]", [](Scenario& s) -> double& { return s.dan.shock_viscosity; }, 0, 1));
    k.push_back(real("dan.shock_viscosity_linear", "-", "c_lin of the bore's dissipation (see dan.shock_viscosity): it damps the block-scale ringing behind the bore that the quadratic term leaves, whatever its amplitude; 0 = none [D16]", [](Scenario& s) -> double& { return s.dan.shock_viscosity_linear; }, 0, 1));
    k.push_back(choice<DanPosition>("dan.position_update", "D14: move each boundary block by its new velocity, S += dt v-hat (symplectic: stable for any number of blocks), or by the mean of the old and new, S += dt (v + v-hat) / 2 (trapezoid: the thesis' eq. 2.31, which amplifies every mode by sqrt(1 + (w dt)^2 / 2) a step and makes more than about 300 blocks crowd)", [](Scenario& s) -> DanPosition& { return s.dan.position_update; }, {{"symplectic", DanPosition::Symplectic}, {"trapezoid", DanPosition::Trapezoid}}));
    k.push_back(real("dan.dt", "s", "time step (dt_mode auto: the largest step allowed)", [](Scenario& s) -> double& { return s.dan.dt; }, 1e-7, 1e-2));
    k.push_back(choice<DanStep>("dan.dt_mode", "a fixed step (the run stops past cfl_max) or the largest within cfl_max", [](Scenario& s) -> DanStep& { return s.dan.dt_mode; }, {{"fixed", DanStep::Fixed}, {"auto", DanStep::Auto}}));
    k.push_back(real("dan.cfl_max", "-", "stability limit: dt (sqrt(k g h cos alpha) + |dv|) / l at most this", [](Scenario& s) -> double& { return s.dan.cfl_max; }, 0, 1, true));
    k.push_back(real("dan.path_extension", "m", "the path goes on straight this far past the barrier's end and before the slope's start", [](Scenario& s) -> double& { return s.dan.path_extension; }, 0, 100));
    // the 3-D solver (scenario.solver = "dem3"; docs/debris.md, "In three dimensions")
    k.push_back(text("dem3.terrain", "the bed: an ESRI ASCII grid (.asc; each cell two triangles) or an x y z point file (.xyz, .txt; triangulated in map view); a relative path is taken from the scenario file's folder", [](Scenario& s) -> std::string& { return s.dem3.terrain; }));
    k.push_back(text("dem3.release_top", "the mass's top surface before failure, as dem3.terrain (.asc or .xyz): the release fills the space between it and the bed inside the release box; empty = dem3.release_thickness above the bed", [](Scenario& s) -> std::string& { return s.dem3.release_top; }));
    k.push_back(real("dem3.release_thickness", "m", "the release's thickness above the bed when there is no dem3.release_top", [](Scenario& s) -> double& { return s.dem3.release_thickness; }, 0, 1e4));
    k.push_back(choice<LatticeLayers>("dem3.release_layers", "the close-packed release's layers: level (Mikhailov's fill) or bed (parallel to the plane fitted to the bed in the release box, the first a radius above it: a slab on a slope that rests on the bed everywhere)", [](Scenario& s) -> LatticeLayers& { return s.dem3.release_layers; }, {{"level", LatticeLayers::Level}, {"bed", LatticeLayers::Bed}}));
    k.push_back(vec2("dem3.release_lo", "m", "the release box's south-west corner in map view [x, y]", [](Scenario& s) -> Vec2& { return s.dem3.release_lo; }));
    k.push_back(vec2("dem3.release_hi", "m", "the release box's north-east corner in map view [x, y]", [](Scenario& s) -> Vec2& { return s.dem3.release_hi; }));
    k.push_back(real("dem3.radius", "m", "the spheres' radius R; the release is close-packed, each inner sphere touching twelve (Mikhailov, Attabad: 10 m)", [](Scenario& s) -> double& { return s.dem3.radius; }, 0, 1e4, true));
    k.push_back(real("dem3.density", "kg/m3", "the spheres' density; m = 4/3 pi R^3 rho (D1; Attabad: 2000)", [](Scenario& s) -> double& { return s.dem3.density; }, 0, 1e5, true));
    k.push_back(real("dem3.youngs_modulus", "Pa", "E of the spheres and of the bed: F = E pi a^2 delta / R (bed), / (Ri + Rj) (pair) (Attabad: 40 GPa)", [](Scenario& s) -> double& { return s.dem3.law.youngs_modulus; }, 0, 1e12, true));
    k.push_back(real("dem3.mu", "-", "dry friction coefficient of a sphere's friction force mu (N + P) against its velocity (Attabad: 0.3)", [](Scenario& s) -> double& { return s.dem3.law.mu; }, 0, 1));
    k.push_back(real("dem3.eta", "N s/m", "viscous friction eta v of a sphere (Attabad: 0)", [](Scenario& s) -> double& { return s.dem3.law.eta; }, 0, 1e15));
    k.push_back(choice<DebrisNormal>("dem3.friction_normal", "N and P of the friction: resultant (the moduli of the summed bed and pair forces) or sum (the sums of their moduli)", [](Scenario& s) -> DebrisNormal& { return s.dem3.law.friction_normal; }, {{"resultant", DebrisNormal::Resultant}, {"sum", DebrisNormal::Sum}}));
    k.push_back(choice<DebrisDirection>("dem3.friction_direction", "the friction against the velocity after the other forces (trial) or the last step's (previous: Mikhailov literally)", [](Scenario& s) -> DebrisDirection& { return s.dem3.law.friction_direction; }, {{"trial", DebrisDirection::Trial}, {"previous", DebrisDirection::Previous}}));
    k.push_back(real("dem3.dt_max", "s", "the automatic step's ceiling, the step of a sphere without contacts (Mikhailov's 0.01 s)", [](Scenario& s) -> double& { return s.dem3.law.dt_max; }, 0, 1, true));
    k.push_back(real("dem3.dt_fixed", "s", "a fixed step instead of the automatic one (0: automatic; 0.01 = Mikhailov's literal run)", [](Scenario& s) -> double& { return s.dem3.law.dt_fixed; }, 0, 1));
    k.push_back(real("dem3.safety", "-", "the automatic step's safety factor on min sqrt(m / K)", [](Scenario& s) -> double& { return s.dem3.law.safety; }, 0, 2, true));
    k.push_back(real("dem3.gravity", "m/s2", "gravity along -z", [](Scenario& s) -> double& { return s.dem3.law.gravity; }, 0, 100));
    k.push_back(real("dem3.raster_cell", "m", "the peak rasters' cell size (0: the terrain grid's, or two radii for a point terrain)", [](Scenario& s) -> double& { return s.dem3.raster_cell; }, 0, 1e5));
    k.push_back(real("dan.sync_time", "s", "the reference front's time the DAN front is synchronised at (thesis Abb. 37: 0.4 s)", [](Scenario& s) -> double& { return s.dan.sync_time; }, 0, 100));
    k.push_back(text("dan.sync_front", "a reference front.csv (a DEM run's, or the lab's digitised) for front_synced.csv; a relative path is taken from the scenario file's folder; empty = none", [](Scenario& s) -> std::string& { return s.dan.sync_front; }));
}

void add_run_keys(std::vector<Key>& k) {
    // release
    k.push_back(integer("release.scale", "-", "upscaling of the sand (Table 14): radii [0.25, 0.5] mm times this (2: 36,403 discs; 4: 9,099; 20: 364)", [](Scenario& s) -> int& { return s.release.scale; }, 1, 100));
    k.push_back(real("release.r_min", "m", "smallest radius before the reduction; 0 = from the scale", [](Scenario& s) -> double& { return s.release.r_min; }, 0, 1));
    k.push_back(real("release.r_max", "m", "largest radius before the reduction; 0 = from the scale", [](Scenario& s) -> double& { return s.release.r_max; }, 0, 1));
    k.push_back(real("release.porosity", "-", "target 2D porosity of the generated mass (Table 5: 0.166)", [](Scenario& s) -> double& { return s.release.porosity; }, 0.05, 0.9));
    k.push_back(real("release.radius_reduction", "-", "fraction all radii shrink by after generation (thesis: 0.03)", [](Scenario& s) -> double& { return s.release.radius_reduction; }, 0, 0.5));
    k.push_back(text("release.variant", "I: the gate is deleted at t = 0; II: the gate is lifted at gate_speed", [](Scenario& s) -> std::string& { return s.release.variant; }, {"I", "II"}));
    k.push_back(real("release.gate_speed", "m/s", "lifting speed of the gate, Variant II (lab: 2.25)", [](Scenario& s) -> double& { return s.release.gate_speed; }, 0, 100, true));
    k.push_back(real("release.settle_stiffness_factor", "-", "the discs' and walls' stiffnesses while the mass compacts without friction, as a fraction of theirs (the frictional phase settles at their own): the compaction is quasi-static, and softer contacts let it take steps 1/sqrt(f) times larger. 1 with settle_alpha = 0.7, settle_friction_alpha = 0 and settle_dashpots = \"centred\": the release of earlier builds, bit for bit (docs/flume.md)", [](Scenario& s) -> double& { return s.release.settle_stiffness_factor; }, 0, 1, true));
    k.push_back(real("release.settle_alpha", "-", "local damping while the mass compacts without friction (earlier builds: 0.7, which slows the compaction)", [](Scenario& s) -> double& { return s.release.settle_alpha; }, 0, 1, false, true));
    k.push_back(real("release.settle_friction_alpha", "-", "local damping while the mass settles with friction, beside the dashpots; 0: on the dashpots alone (earlier builds; 0.7 makes the mass chatter)", [](Scenario& s) -> double& { return s.release.settle_friction_alpha; }, 0, 1, false, true));
    k.push_back(text("release.settle_dashpots", "how the dashpots are integrated while the mass settles (timestep.dashpots): lagged (with the damping correction: the settling is quasi-static, and a lagged step costs half a centred one) or centred (earlier builds, whose runs settled with the run's scheme, centred by default)", [](Scenario& s) -> std::string& { return s.release.settle_dashpots; }, {"lagged", "centred"}));
    k.push_back(real("release.settle_ratio", "-", "settled when mean |unbalanced force| / mean |contact force| falls below this", [](Scenario& s) -> double& { return s.release.settle_ratio; }, 0, 1, true));
    k.push_back(real("release.settle_max_time", "s", "simulated settling time at most (the run refuses a mass that did not settle)", [](Scenario& s) -> double& { return s.release.settle_max_time; }, 0, 100, true));
    k.push_back(boolean("release.accept_unsettled", "run a release mass that did not reach settle_ratio within settle_max_time (its ratio is in summary.json); false: such a mass is refused (exit 3)", [](Scenario& s) -> bool& { return s.release.accept_unsettled; }));
    k.push_back(real("release.layer_height", "m", "height of the horizontal colour bands (layers)", [](Scenario& s) -> double& { return s.release.layer_height; }, 0, 10, true));
    k.push_back(real("release.grid_cell", "m", "size of the colour grid's cells", [](Scenario& s) -> double& { return s.release.grid_cell; }, 0, 10, true));
    k.push_back(text("release.space_order", "number the generated discs in space order before they settle, so that the settling runs on all threads: on, off, or auto (on above 1,000 discs). A different numbering settles into a different, equally valid mass", [](Scenario& s) -> std::string& { return s.release.space_order; }, {"auto", "on", "off"}));
    k.push_back(text("release.settle_ramp", "how the frictionless settling reaches the real stiffness: smooth = the compaction at a quarter of settle_stiffness_factor (to 20 times settle_ratio), then one frictionless stage that raises the stiffness continuously to the real one over two periods of the mass' slowest mode (about 42 sqrt(N) steps); on = the same compaction (to 10 times settle_ratio), then frictionless stages at four times the stiffness each (the intermediate ones to 50 times settle_ratio) up to the real one; off = the compaction at settle_stiffness_factor, then one stage at the real stiffness; auto = smooth above 20,000 discs, else off. Geometry A at scale 2: 113,600 (off), 74,400 (on) and 55,800 (smooth) settling steps (docs/flume.md)", [](Scenario& s) -> std::string& { return s.release.settle_ramp; }, {"auto", "on", "off", "smooth"}));
    k.push_back(text("release.from_file", "a settled mass (release.csv of an earlier run) to start from instead of generating one (a relative path is taken from the scenario file's folder; --release-from's from the working directory)", [](Scenario& s) -> std::string& { return s.release.from_file; }));
    // stop
    k.push_back(real("stop.t_max", "s", "simulated time after the release at most", [](Scenario& s) -> double& { return s.stop.t_max; }, 0, 1e4, true));
    k.push_back(real("stop.rest_ke_fraction", "-", "at rest when the kinetic energy stays below this fraction of its peak ...", [](Scenario& s) -> double& { return s.stop.rest_ke_fraction; }, 0, 1, true));
    k.push_back(integer("stop.max_steps", "-", "steps at most, counted from t = 0 (0: no limit); a run that reaches it ends with stop_reason \"max_steps\" and its outputs complete (a bound on the work of a trial or a scripted run)", [](Scenario& s) -> int& { return s.stop.max_steps; }, 0, 2000000000));
    k.push_back(real("stop.rest_duration", "s", "... for this long", [](Scenario& s) -> double& { return s.stop.rest_duration; }, 0, 100));
    k.push_back(real("stop.max_energy_gain", "-", "blow-up watch: the run stops when the energy balance (kinetic + potential + elastic + dissipated - work of moving walls) has risen by more than this multiple of the energy turned over (peak kinetic + peak elastic + dissipated): the numerics are creating energy", [](Scenario& s) -> double& { return s.stop.max_energy_gain; }, 0, 10, true));
    // output
    k.push_back(real("output.series_interval", "s", "time between rows of forces.csv, front.csv, energy.csv, track.csv", [](Scenario& s) -> double& { return s.output.series_interval; }, 0, 100, true));
    k.push_back(text("output.snapshot_format", "the snapshots' arrays: binary (appended raw, zlib-compressed; ParaView and demlab render read both) or ascii (text)", [](Scenario& s) -> std::string& { return s.output.snapshot_format; }, {"binary", "ascii"}));
    k.push_back(real("output.snapshot_interval", "s", "time between snapshots (VTK .vtp with a .pvd series); 0 = none", [](Scenario& s) -> double& { return s.output.snapshot_interval; }, 0, 100));
    k.push_back(real("output.pressure_bin", "m", "bin length of barrier_pressure.csv along the barrier from its lower end, at least the largest disc's diameter (the count is round(length / bin); summary.json's barrier_pressure_bin)", [](Scenario& s) -> double& { return s.output.pressure_bin; }, 0, 10, true));
    k.push_back(real("output.load_window", "s", "window W of the impulse-filtered loads: the mean force over the last W, the impulse gained over it divided by its length (summary.json's peak_fx_barrier_filtered, peak_fy_arc_filtered)", [](Scenario& s) -> double& { return s.output.load_window; }, 0, 10, true));
    k.push_back(real("output.approach_length", "m", "length of bed upstream of the barrier's foot where the arriving flow is measured when the front reaches the barrier (summary.json's approach_depth, approach_speed, approach_mass_per_length, impact_coefficient_alpha); 0 = 20 times the largest radius", [](Scenario& s) -> double& { return s.output.approach_length; }, 0, 1e4));
    k.push_back(integer("output.force_history_steps", "-", "steps between the rows of force_history.csv, the forces on the wall groups as PFC's dense wall-force history (1 = every step); 0 = none", [](Scenario& s) -> int& { return s.output.force_history_steps; }, 0, 1000000000));
    k.push_back(real("output.deposit_bin", "m", "spacing of deposit.csv along the bed path (and of peaks.csv), and of surface.csv in x", [](Scenario& s) -> double& { return s.output.deposit_bin; }, 0, 10, true));
    k.push_back(real("output.front_neighbour_gap", "m", "a disc counts for the front only with a neighbour within this gap; 0 = r_max", [](Scenario& s) -> double& { return s.output.front_neighbour_gap; }, 0, 10));
    {
        Key track{"output.track", "-", "array of disc ids >= 0", "disc ids written to track.csv (tracer discs)", nullptr, nullptr};
        track.set = [](Scenario& s, const toml::node& n, const std::string& where) {
            const toml::array* a = n.as_array();
            if (!a) throw InputError(where + " = " + node_text(n) + ": must be an array of disc ids, e.g. [0, 17]");
            s.output.track.clear();
            for (const auto& e : *a) {
                auto v = e.value_exact<int64_t>();
                if (!v || *v < 0) throw InputError(where + ": entry " + node_text(e) + " must be a disc id >= 0");
                s.output.track.push_back(long(*v));
            }
        };
        track.get = [](const Scenario& s) {
            std::string out = "[";
            for (size_t i = 0; i < s.output.track.size(); ++i) out += (i ? ", " : "") + std::to_string(s.output.track[i]);
            return out + "]";
        };
        k.push_back(track);
    }
}

}  // namespace

// The table, in the order of the reference page and the resolved scenario.
const std::vector<Key>& registry() {
    static const std::vector<Key> keys = [] {
        std::vector<Key> k;
        add_scenario_and_material_keys(k);
        add_dynamics_keys(k);
        add_setups_keys(k);
        add_cohesion_keys(k);
        add_dan_keys(k);
        add_run_keys(k);
        return k;
    }();
    return keys;
}

size_t edit_distance(const std::string& a, const std::string& b) {
    std::vector<size_t> prev(b.size() + 1), cur(b.size() + 1);
    for (size_t j = 0; j <= b.size(); ++j) prev[j] = j;
    for (size_t i = 1; i <= a.size(); ++i) {
        cur[0] = i;
        for (size_t j = 1; j <= b.size(); ++j)
            cur[j] = std::min({prev[j] + 1, cur[j - 1] + 1, prev[j - 1] + (a[i - 1] == b[j - 1] ? 0 : 1)});
        std::swap(prev, cur);
    }
    return prev[b.size()];
}

std::string nearest(const std::string& key, const std::vector<std::string>& names) {
    std::string best;
    size_t best_d = 1000;
    for (const auto& n : names) {
        const size_t d = edit_distance(key, n);
        if (d < best_d) {
            best_d = d;
            best = n;
        }
    }
    return best_d <= std::max<size_t>(3, key.size() / 3) ? best : std::string();
}

const Key* find_key(const std::string& name) {
    for (const Key& k : registry())
        if (k.name == name) return &k;
    return nullptr;
}

std::vector<std::string> key_names() {
    std::vector<std::string> names;
    for (const Key& k : registry()) names.push_back(k.name);
    return names;
}

[[noreturn]] void unknown_key(const std::string& where, const std::string& key, const std::vector<std::string>& names) {
    const std::string near = nearest(key, names);
    throw InputError(where + ": unknown key" + (near.empty() ? std::string() : "; did you mean '" + near + "'?") +
                     " (docs/scenario-reference.md lists every key)");
}

}  // namespace demlab::keys
