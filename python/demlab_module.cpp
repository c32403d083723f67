// The compiled part of the Python module `demlab` (python/demlab/__init__.py wraps it): the
// scenario with its key registry and checks, runs into run folders, and a World to step from
// Python. It calls the C++ library, never the executable, so a run from Python writes the same
// files, with the same bytes, as `demlab run`.
#include <filesystem>
#include <pybind11/functional.h>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <algorithm>
#include <cstdio>
#include <memory>
#include <regex>
#include <string>

#include "core/error.h"
#include "core/interrupt.h"
#include "core/validate.h"
#include "output/plot.h"
#include "output/render_run.h"
#include "run/measures.h"
#include "run/run.h"
#include "run/solver.h"
#include "scenario/key_registry.h"
#include "scenario/scenario.h"
#include "setups/setup.h"

namespace py = pybind11;
using namespace demlab;

namespace {

// A scenario as Python holds it: the parsed keys (with the overrides applied) and, once
// checked, the finished scenario. Kept apart so that an override after loading is checked
// against every key again.
struct PyScenario {
    Scenario s;
    std::string path;
};

// The registry's key named first in an error message (the longest, so that "release.variant"
// wins over a shorter prefix), or "".
std::string key_in_message(const std::string& message) {
    std::string best;
    for (const keys::Key& k : keys::registry())
        if (k.name.size() > best.size() && message.find(k.name) != std::string::npos) best = k.name;
    return best;
}

// The executable's words in a message, as this module's: --set 'key=value' is load_scenario's
// overrides['key'], --out and --force are run()'s out= and force=True, --release-from and
// --threads the arguments of the same names.
std::string python_terms(std::string m) {
    static const std::regex set_override("--set '([^'=]+)=[^']*'");
    m = std::regex_replace(m, set_override, "overrides['$1']");
    static const std::regex set_key("--set key '([^']+)'");  // (a value out of its range)
    m = std::regex_replace(m, set_key, "overrides['$1']");
    // the options as words only: "--out" inside a path ("/tmp/x--out") is the path's
    for (const auto& [cli, py] : {std::pair<std::string, std::string>{"--release-from", "release_from="},
                                  {"--out", "out="}, {"--force", "force=True"}, {"--threads", "threads="}}) {
        const std::regex word("(^|[\\s(;,])" + cli + "(?![\\w/.-])");
        m = std::regex_replace(m, word, "$1" + py);
    }
    return m;
}

// A Python value as a TOML literal for apply_override: bools, numbers, strings, lists of them.
std::string toml_literal(const py::handle& v) {
    if (py::isinstance<py::bool_>(v)) return v.cast<bool>() ? "true" : "false";
    if (py::isinstance<py::int_>(v)) {
        // TOML's integers are 64-bit: a larger one is refused here, with its key (load)
        long long x = 0;
        try {
            x = v.cast<long long>();
        } catch (const py::cast_error&) {
            throw InputError("the integer " + std::string(py::str(v)) + " is beyond a 64-bit integer's range [-2^63, 2^63 - 1]");
        }
        return std::to_string(x);
    }
    if (py::isinstance<py::float_>(v)) return keys::toml_number(v.cast<double>());
    if (py::isinstance<py::str>(v)) return keys::toml_string(v.cast<std::string>());
    if (py::isinstance<py::list>(v) || py::isinstance<py::tuple>(v)) {
        std::string out = "[";
        bool first = true;
        for (const py::handle& item : v) {
            if (!first) out += ", ";
            out += toml_literal(item);
            first = false;
        }
        return out + "]";
    }
    if (py::hasattr(v, "tolist")) return toml_literal(v.attr("tolist")());  // numpy scalars and arrays
    throw InputError("a value of Python type '" + std::string(py::str(v.get_type().attr("__name__"))) +
                     "' has no TOML form (give a bool, number, string or list)");
}

// An InputError raised while one override was applied: its key is the one the user gave.
struct KeyedInputError : InputError {
    KeyedInputError(const std::string& what, std::string k) : InputError(what), key(std::move(k)) {}
    std::string key;
};

PyScenario load(const std::string& path, const py::dict& overrides, const std::string& release_from) {
    PyScenario p{load_scenario(path), path};
    for (const auto& [key, value] : overrides) {
        const std::string k = py::str(key);
        try {
            apply_override(p.s, k + "=" + toml_literal(value));
        } catch (const InputError& e) {
            throw KeyedInputError(e.what(), k);
        }
    }
    // the working directory's, as --release-from (kept absolute: the run folder's scenario.toml
    // and a resume read the same file from anywhere)
    if (!release_from.empty()) p.s.release.from_file = std::filesystem::absolute(release_from).lexically_normal().string();
    finish_scenario(p.s);
    return p;
}

// The run of `demlab run` (run_scenario, then the plots), without its console lines.
void run(PyScenario sc, const std::string& out, int threads, bool force, bool frames, bool plots,
               double checkpoint_every, const py::object& progress) {
    if (threads < 1 || threads > 64) throw InputError("threads = " + std::to_string(threads) + ": must be 1 to 64");
    // as the executable's --checkpoint-every, and a progress that can be called, before any output
    if (!(checkpoint_every >= 0.0 && checkpoint_every <= 1e7))
        throw InputError("checkpoint_every = " + format_number(checkpoint_every) + ": must be seconds in [0, 1e7]");
    if (!progress.is_none() && !PyCallable_Check(progress.ptr()))
        throw InputError("progress: must be None or a function progress(t, t_max, rate)");
    Scenario& s = sc.s;
    s.world.threads = threads;
    RunOptions ro;
    ro.out_dir = out.empty() ? "runs/" + s.name : out;
    ro.force = force;
    ro.checkpoint_every = checkpoint_every;
    ro.handle_signals = true;  // Ctrl-C: a final checkpoint, then demlab.Interrupted
    ro.frames = frames;
    ro.plots = plots;
    if (!progress.is_none()) {
        ro.on_progress = [progress](double t, double t_max, double rate) {
            py::gil_scoped_acquire gil;
            progress(t, t_max, rate);
        };
    }
    if (frames && s.solver != "dan") attach_frame_hook(ro, make_setup(s)->kind() == "flume");
    {
        py::gil_scoped_release nogil;
        run_scenario(s, ro);
        if (frames && s.solver == "dan") {
            RenderRunOptions f;
            f.run_dir = ro.out_dir;
            f.force = force;
            render_run(f);
        }
        if (plots && gnuplot_available()) make_plots(ro.out_dir);
    }
}

// A finalized world of a scenario, owned by Python, with the run loop's energy watch
// (run.cpp): every kEnergyWatchSteps steps, when a disc is lost and when a step fails, a
// ledger that gained more than stop.max_energy_gain times the energy put in (or is not
// finite) raises RunError, as `demlab run` exits 3.
struct PyWorld {
    std::unique_ptr<World> w;
    double e0 = 0.0, noise = 0.0, max_gain = 1.0, peak_put_in = 0.0;
    DissipationPeaks dissipation;  // (a damper that makes energy is a blow-up there too)
    size_t lost_seen = 0;

    void watch() {
        const DemSolver solver(*w);
        check_energy_growth(solver, e0, max_gain, noise, peak_put_in, dissipation);
    }
    void step(long n) {
        for (long k = 0; k < n; ++k) {
            try {
                w->step();
            } catch (const RunError&) {
                watch();  // a lost disc or an overlap after energy was created: named as a runaway
                throw;
            }
            if (w->lost_discs().size() != lost_seen) {
                lost_seen = w->lost_discs().size();
                watch();
            }
            if (w->step_count() % kEnergyWatchSteps == 0) watch();
        }
    }
};

// A read-only numpy view of a world's array, kept alive by the Python World (base).
template <typename T>
py::array view(const std::vector<T>& v, const py::object& base) {
    py::array a(py::dtype::of<T>(), {py::ssize_t(v.size())}, {py::ssize_t(sizeof(T))}, v.data(), base);
    py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return a;
}
py::array view_xy(const std::vector<Vec2>& v, const py::object& base) {
    static_assert(sizeof(Vec2) == 2 * sizeof(double), "Vec2 is two packed doubles");
    py::array a(py::dtype::of<double>(), {py::ssize_t(v.size()), py::ssize_t(2)},
                {py::ssize_t(sizeof(Vec2)), py::ssize_t(sizeof(double))}, v.empty() ? nullptr : v[0].data(), base);
    py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
    return a;
}

py::dict energy_dict(const EnergyReport& e) {
    py::dict d;
    d["kinetic_translation"] = e.kinetic_translation;
    d["kinetic_rotation"] = e.kinetic_rotation;
    d["potential"] = e.potential;
    d["elastic"] = e.elastic;
    d["dissipated_contacts"] = e.dissipated_contacts;
    d["dissipated_local"] = e.dissipated_local;
    d["dissipated_rotation"] = e.dissipated_rotation;
    d["work_by_walls"] = e.work_by_walls;
    d["removed_with_walls"] = e.removed_with_walls;
    d["bond_elastic"] = e.bond_elastic;
    d["bond_break_loss"] = e.bond_break_loss;
    d["lost_with_discs"] = e.lost_with_discs;
    d["balance"] = e.balance();
    return d;
}

}  // namespace

PYBIND11_MODULE(_demlab, m) {
    m.doc() = "The compiled part of demlab; use the package `demlab`, which documents it.";

    // the error taxonomy of the executable: InputError (exit code 2), RunError (3), and an
    // interrupted run (4), which is a KeyboardInterrupt to Python
    static py::exception<InputError> input_error(m, "InputError", PyExc_ValueError);
    static py::exception<RunError> run_error(m, "RunError", PyExc_RuntimeError);
    static py::exception<Interrupted> interrupted(m, "Interrupted", PyExc_KeyboardInterrupt);
    input_error.doc() = "Bad input (exit code 2 of the executable): the message names the file, key, value and "
                        "accepted range; `key` is the scenario key concerned (\"\" if none).";
    run_error.doc() = "A run that failed or blew up (exit code 3): the message says what and when.";
    interrupted.doc() = "A run stopped by Ctrl-C (exit code 4): a checkpoint is written; `demlab resume RUN_DIR` continues it.";
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const KeyedInputError& e) {
            py::object type = py::reinterpret_borrow<py::object>(input_error);
            py::object err = type(py::str(python_terms(e.what())));
            err.attr("key") = e.key;
            PyErr_SetObject(input_error.ptr(), err.ptr());
        } catch (const InputError& e) {
            py::object type = py::reinterpret_borrow<py::object>(input_error);
            py::object err = type(py::str(python_terms(e.what())));
            err.attr("key") = key_in_message(e.what());
            PyErr_SetObject(input_error.ptr(), err.ptr());
        } catch (const RunError& e) {
            run_error(python_terms(e.what()).c_str());
        } catch (const Interrupted& e) {
            interrupted(e.what());
        }
    });

    py::class_<PyScenario>(m, "Scenario", "A checked scenario: every key of `demlab keys` with its value.")
        .def("to_toml", [](const PyScenario& p) { return resolved_toml(p.s); },
             "The resolved scenario as TOML: every key with its value (what a run writes as scenario.toml).")
        .def("get", [](const PyScenario& p, const std::string& key) {
                 const keys::Key* k = keys::find_key(key);
                 // the error names the key asked for, as Python wrote it, and carries it as `key`
                 if (!k) try {
                         keys::unknown_key("scenario['" + key + "']", key, keys::key_names());
                     } catch (const InputError& e) {
                         throw KeyedInputError(e.what(), key);
                     }
                 return k->get(p.s);
             }, py::arg("key"), "The value of one key as a TOML literal (demlab.Scenario.__getitem__ parses it).")
        .def_property_readonly("name", [](const PyScenario& p) { return p.s.name; }, "scenario.name")
        .def_property_readonly("path", [](const PyScenario& p) { return p.path; }, "the file it was read from")
        .def_property_readonly("solver", [](const PyScenario& p) { return p.s.solver; }, "dem or dan");

    m.def("load_scenario", &load, py::arg("path"), py::arg("overrides") = py::dict(), py::arg("release_from") = "",
          "Reads a scenario file, applies overrides {key: value} (as --set key=value does) and checks it.");
    m.def("key_names", &keys::key_names, "Every scenario key, in the order of `demlab keys`.");
    m.def("run", &run, py::arg("scenario"), py::arg("out"), py::arg("threads") = 1, py::arg("force") = false,
          py::arg("frames") = false, py::arg("plots") = true, py::arg("checkpoint_every") = 0.0,
          py::arg("progress") = py::none(), "Runs a scenario into the run folder `out`, as `demlab run` does.");

    py::class_<PyWorld>(m, "World", "A DEM world built from a scenario, stepped from Python.")
        .def_static("from_scenario", [](const PyScenario& p, int threads) {
                if (p.s.solver != "dem") throw InputError("World.from_scenario: scenario.solver = \"" + p.s.solver +
                                                          "\": a World is the discs' (dem) model");
                if (threads < 1 || threads > 64) throw InputError("threads = " + std::to_string(threads) + ": must be 1 to 64");
                Scenario s = p.s;
                s.world.threads = threads;
                PyWorld w;
                py::gil_scoped_release nogil;
                w.w.reset(new World(world_of_scenario(s)));  // built in place, not moved
                w.e0 = w.w->energy().balance();
                w.dissipation = DissipationPeaks(w.w->energy());
                w.noise = ledger_noise(*w.w, s.world.gravity.norm());
                w.max_gain = s.stop.max_energy_gain;
                w.lost_seen = w.w->lost_discs().size();
                return w;
            }, py::arg("scenario"), py::arg("threads") = 1)
        .def("step", [](PyWorld& w, long n) {
                if (n < 0) throw InputError("World.step(" + std::to_string(n) + "): the number of steps must be >= 0");
                // in pieces, with Python's signals looked at between them: Ctrl-C raises
                // KeyboardInterrupt within a piece's time (the steps are the same whatever the pieces)
                constexpr long kPiece = 2000;
                for (long done = 0; done < n;) {
                    const long piece = std::min(kPiece, n - done);
                    {
                        py::gil_scoped_release nogil;
                        w.step(piece);
                    }
                    done += piece;
                    if (PyErr_CheckSignals() != 0) throw py::error_already_set();
                }
            }, py::arg("n") = 1)
        .def_property_readonly("time", [](const PyWorld& w) { return w.w->time(); })
        .def_property_readonly("dt", [](const PyWorld& w) { return w.w->dt(); })
        .def_property_readonly("step_count", [](const PyWorld& w) { return w.w->step_count(); })
        .def_property_readonly("disc_count", [](const PyWorld& w) { return w.w->disc_count(); })
        .def_property_readonly("positions", [](py::object self) { return view_xy(self.cast<PyWorld&>().w->positions(), self); })
        .def_property_readonly("velocities", [](py::object self) { return view_xy(self.cast<PyWorld&>().w->velocities(), self); })
        .def_property_readonly("radii", [](py::object self) { return view(self.cast<PyWorld&>().w->radii(), self); })
        .def_property_readonly("masses", [](py::object self) { return view(self.cast<PyWorld&>().w->masses(), self); })
        .def_property_readonly("angles", [](py::object self) { return view(self.cast<PyWorld&>().w->angles(), self); })
        .def_property_readonly("omegas", [](py::object self) { return view(self.cast<PyWorld&>().w->omegas(), self); })
        .def_property_readonly("ids", [](py::object self) { return view(self.cast<PyWorld&>().w->disc_ids(), self); })
        .def("wall_forces", [](const PyWorld& w) {
                const size_t n = w.w->wall_count();
                py::array_t<double> a({py::ssize_t(n), py::ssize_t(2)});
                auto r = a.mutable_unchecked<2>();
                for (size_t k = 0; k < n; ++k) {
                    const Vec2 f = w.w->wall_force(int(k));
                    r(py::ssize_t(k), 0) = f.x();
                    r(py::ssize_t(k), 1) = f.y();
                }
                return a;
            })
        .def("wall_active", [](const PyWorld& w, int k) {
                if (k < 0 || size_t(k) >= w.w->wall_count()) throw InputError("World.wall_active(" + std::to_string(k) + "): no such wall");
                return w.w->wall_active(k);
            }, py::arg("wall"))
        .def_property_readonly("wall_count", [](const PyWorld& w) { return w.w->wall_count(); })
        .def("energy", [](const PyWorld& w) { return energy_dict(w.w->energy()); })
        .def("kinetic_energy", [](const PyWorld& w) { return w.w->kinetic_energy(); });
}
