"""demlab from Python: granular flows with the discrete element method.

The module wraps the C++ library that the `demlab` executable is built on: a run from Python
writes the same run folder, with the same bytes, as `demlab run`.

    import demlab
    sc = demlab.load_scenario("scenarios/geometry-A.toml", {"release.scale": 20})
    folder = demlab.run(sc, "runs/a20", threads=2)
    print(folder.summary["runout_s"], folder.forces["fx_barrier_N_per_m"].max())
    snap = folder.snapshot(-1)            # the last snapshot: positions (N x 2), radii, ...

    world = demlab.World.from_scenario(sc)
    world.step(1000)
    print(world.time, world.positions[:3])

Units are SI throughout (m, s, kg, N); forces and energies are per metre of thickness
(the model is 2-D, 1 m thick, as PFC2D). Every CSV column names its unit (t_s,
fx_barrier_N_per_m, ...), and summary["units"] names the unit of every summary number.

Errors: a bad scenario or value raises demlab.InputError (a ValueError) with the message the
executable prints and its `key`; a run that fails raises demlab.RunError; Ctrl-C during
demlab.run writes a checkpoint and raises demlab.Interrupted (a KeyboardInterrupt), after
which `demlab resume RUN_DIR` continues the run to the same results.
"""
import csv as _csv
import json as _json
import math as _math
import os as _os
import tomllib as _tomllib
import xml.etree.ElementTree as _ET
import zlib as _zlib

import numpy as _np

from . import _demlab
from ._demlab import InputError, Interrupted, RunError

__all__ = ["load_scenario", "run", "RunFolder", "Scenario", "World", "Snapshot", "InputError", "RunError",
           "Interrupted", "key_names"]


class Scenario:
    """A checked scenario: every key of `demlab keys` with its value.

    Made by demlab.load_scenario. `scenario["material.friction_disc_deg"]` reads a key's value
    (as TOML gives it: float, int, str, bool or list), `scenario.to_toml()` the resolved
    scenario, `scenario.with_overrides({...})` a changed copy, checked again.
    """

    def __init__(self, compiled, path, overrides, release_from):
        self._compiled = compiled
        self._path = path
        self._overrides = dict(overrides)
        self._release_from = release_from

    @property
    def name(self):
        """scenario.name: the default run folder is runs/NAME"""
        return self._compiled.name

    @property
    def path(self):
        """the scenario file it was read from"""
        return self._path

    @property
    def overrides(self):
        """the overrides applied on top of the file, {key: value}"""
        return dict(self._overrides)

    def to_toml(self):
        """the resolved scenario as TOML text (what a run writes as scenario.toml)"""
        return self._compiled.to_toml()

    def __getitem__(self, key):
        """the value of a key, e.g. scenario["release.variant"] -> "II"; an unknown key raises
        InputError with the nearest names"""
        return _tomllib.loads("v = " + self._compiled.get(key))["v"]

    def keys(self):
        """every key name, in the order of `demlab keys`"""
        return _demlab.key_names()

    def __contains__(self, key):
        """whether `key` is a scenario key: "release.scale" in scenario"""
        return isinstance(key, str) and key in _demlab.key_names()

    def __iter__(self):
        """the key names, as keys()"""
        return iter(_demlab.key_names())

    def with_overrides(self, overrides):
        """a copy with more overrides {key: value}, checked as load_scenario checks"""
        merged = dict(self._overrides)
        merged.update(overrides)
        return load_scenario(self._path, merged, self._release_from)

    def __repr__(self):
        return "demlab.Scenario(%r, %r)" % (self._path, self._overrides)


def load_scenario(path, overrides=None, release_from=None):
    """Reads a scenario file (TOML) and applies `overrides`, {key: value}, as `demlab run --set
    key=value` does (values as Python bools, numbers, strings or lists). `release_from` names
    the release.csv of an earlier run to start from its settled mass (--release-from).

    The same checks as the executable: an unknown key, a wrong type or a value out of its
    range raises demlab.InputError with the file, key, value and accepted range; the error's
    `key` attribute names the key.
    """
    overrides = dict(overrides or {})
    for name, value in (("path", path), ("release_from", release_from)):
        if value is not None and "\0" in str(value):  # (the system would take the name up to it)
            raise InputError("load_scenario(%s=%r): a path cannot hold a NUL character" % (name, str(value)))
    compiled = _demlab.load_scenario(str(path), overrides, "" if release_from is None else str(release_from))
    return Scenario(compiled, str(path), overrides, release_from)


def key_names():
    """every scenario key, in the order of `demlab keys`"""
    return _demlab.key_names()


def run(scenario, out=None, threads=1, progress=None, force=False, frames=False, plots=True, checkpoint_every=0.0):
    """Runs a scenario (a demlab.Scenario or a file path) into the run folder `out`, as `demlab
    run` does: the same files with the same bytes, for any thread count. Returns a RunFolder.
    out: a path, or None for runs/<scenario.name> (as the executable without --out).

    progress: None, or a callable given (t, t_max, steps_per_second) about four times a second
    (s, s, 1/s). frames: render a PNG at every snapshot (out/frames). plots: the gnuplot plots
    at the end (out/plots). checkpoint_every: seconds of wall-clock time between checkpoints
    (0: only on Ctrl-C). An existing folder is refused unless force=True. Ctrl-C writes a
    checkpoint and raises demlab.Interrupted; `demlab resume out` continues the run.
    """
    if not isinstance(scenario, Scenario):
        scenario = load_scenario(scenario)
    if out is None:  # the executable's default: runs/<scenario.name>
        out = _os.path.join("runs", scenario.name)
    elif not isinstance(out, (str, bytes, _os.PathLike)):
        raise InputError("run(out=%r): the output folder must be a path (str or os.PathLike) or None for runs/<scenario.name>"
                         % (out,))
    out = _os.fsdecode(_os.fspath(out))
    if not out:
        raise InputError("run(out=''): an output folder needs a name")
    if "\0" in out:  # (the system would take the name up to it)
        raise InputError("run(out=%r): a path cannot hold a NUL character" % (out,))
    _demlab.run(scenario._compiled, out, int(threads), bool(force), bool(frames), bool(plots),
                float(checkpoint_every), progress)
    return RunFolder(out)


class World:
    """A DEM world built from a scenario (its release mass, walls and bonds), stepped from
    Python, for measurements of one's own. The arrays are read-only numpy views of the
    world's own memory (no copy), in the order of the discs as they are now: read them again
    after step(), since a disc that leaves the domain is taken out (world.lost_discs) and the
    order then changes; `ids` gives each row's disc id.

        w = demlab.World.from_scenario(sc)
        w.step(1000)                      # 1,000 steps, as 1,000 steps of `demlab run`
        v = w.velocities                  # (N, 2), m/s
    """

    def __init__(self, compiled):
        self._w = compiled

    @staticmethod
    def from_scenario(scenario, threads=1):
        """the world a run of `scenario` (a Scenario or a path) starts from, at t = 0 (a flume's
        release mass is generated first, or read with load_scenario's release_from)"""
        if not isinstance(scenario, Scenario):
            scenario = load_scenario(scenario)
        return World(_demlab.World.from_scenario(scenario._compiled, int(threads)))

    def step(self, n=1):
        """advances n steps (the step is the scenario's: automatic or fixed)"""
        self._w.step(int(n))

    time = property(lambda self: self._w.time, doc="simulated time, s")
    dt = property(lambda self: self._w.dt, doc="the next step, s")
    step_count = property(lambda self: self._w.step_count, doc="steps taken since t = 0")
    disc_count = property(lambda self: self._w.disc_count, doc="discs in the world now")
    positions = property(lambda self: self._w.positions, doc="disc centres, (N, 2), m")
    velocities = property(lambda self: self._w.velocities, doc="disc velocities, (N, 2), m/s")
    radii = property(lambda self: self._w.radii, doc="disc radii, (N,), m")
    masses = property(lambda self: self._w.masses, doc="disc masses, (N,), kg per m of thickness")
    angles = property(lambda self: self._w.angles, doc="disc rotation angles, (N,), rad")
    omegas = property(lambda self: self._w.omegas, doc="disc angular velocities, (N,), rad/s")
    ids = property(lambda self: self._w.ids, doc="the id of each row (its index when the world was built), (N,)")
    wall_count = property(lambda self: self._w.wall_count, doc="walls, removed ones included")

    def wall_forces(self):
        """the force of the discs on each wall in the last step, (n_walls, 2), N per m of
        thickness; the flume's walls are W1 slope (0), W2 arc (1), W3 barrier (2), W4 gate,
        W5 lid"""
        return self._w.wall_forces()

    def wall_active(self, k):
        """whether wall k is present now (a gate is removed once lifted clear)"""
        return self._w.wall_active(int(k))

    def energy(self):
        """the energy ledger, J per m of thickness: kinetic, potential, elastic, the dissipated
        parts, the work of moving walls and `balance` (constant up to round-off)"""
        return self._w.energy()

    def kinetic_energy(self):
        """kinetic energy of the discs after the last step, J per m of thickness"""
        return self._w.kinetic_energy()


def _read_csv(path):
    with open(path, newline="") as f:
        text = f.read()
    # release.csv opens with its generation figures as "# name value" lines
    lines = text.splitlines()
    skipped = 0
    while skipped < len(lines) and lines[skipped].startswith("#"):
        skipped += 1
    rows = list(_csv.reader(lines[skipped:]))
    if not rows:
        raise InputError("%s: an empty CSV file" % path)
    # a run writes whole lines: a last line without its line end, or a row whose cells do not
    # match the header, is a file cut short (a full disk, a killed writer)
    if not text.endswith("\n"):
        raise InputError("%s:%d: the last line has no line end: the file is cut short" % (path, len(rows)))
    head, body = rows[0], []
    for line, r in enumerate(rows[1:], start=2 + skipped):
        if not r:
            continue
        if len(r) != len(head):
            raise InputError("%s:%d: %d cells, the header has %d: the row is cut short or malformed"
                             % (path, line, len(r), len(head)))
        body.append(r)
    out = {}
    for j, name in enumerate(head):
        # an empty cell is a value not measured at that row (forces.csv's filtered loads before
        # the first whole window): NaN, as the executable reads it, so the column stays numbers
        col = [r[j] if r[j] != "" else "nan" for r in body]
        try:
            out[name] = _np.array(col, dtype=float)
        except ValueError:
            out[name] = _np.array([r[j] for r in body])
    return out


class Snapshot:
    """One instant of a run's snapshots (snapshots/discs_NNNNN.vtp): numpy arrays of the discs.

    time (s), positions (N, 2) m, radii (N,) m, velocities (N, 2) m/s, speeds (N,) m/s, angles
    (N,) rad, omegas (N,) rad/s, layers and grids (N,) colour tags of the release mass, ids
    (N,); with bonds also bonds_intact and bonds_broken (N,).
    """

    def __init__(self, arrays, time):
        self.time = time
        pts = arrays["Points"].reshape(-1, 3)
        self.positions = pts[:, :2].copy()
        self.radii = arrays["radius"]
        self.velocities = arrays["velocity"].reshape(-1, 3)[:, :2].copy()
        self.speeds = arrays["speed"]
        self.angles = arrays["angle"]
        self.omegas = arrays["omega"]
        self.layers = arrays["layer"]
        self.grids = arrays["grid"]
        self.ids = arrays["id"]
        self.bonds_intact = arrays.get("bonds_intact")
        self.bonds_broken = arrays.get("bonds_broken")

    def __len__(self):
        return len(self.radii)


_VTK_TYPES = {"Float64": "<f8", "Float32": "<f4", "Int32": "<i4", "Int64": "<i8", "UInt8": "<u1", "UInt32": "<u4",
              "UInt64": "<u8"}


def read_vtp(path):
    """the point and field arrays of a VTK XML PolyData file as written by demlab (ASCII, or
    appended raw binary, zlib-compressed or not), {name: numpy array}"""
    with open(path, "rb") as f:
        data = f.read()
    cut = data.find(b"<AppendedData")
    appended = b""
    if cut >= 0:
        start = data.index(b"_", cut) + 1
        end = data.rindex(b"</AppendedData>")
        appended = data[start:end].rstrip(b"\n ")
        xml = data[:cut] + b"</VTKFile>\n"
    else:
        xml = data
    root = _ET.fromstring(xml)
    compressed = root.get("compressor") == "vtkZLibDataCompressor"
    header = "<u8" if root.get("header_type") == "UInt64" else "<u4"
    hsize = _np.dtype(header).itemsize
    out = {}
    for el in root.iter("DataArray"):
        name, dtype = el.get("Name"), _VTK_TYPES[el.get("type")]
        if el.get("format") == "appended":
            off = int(el.get("offset"))
            if compressed:
                nblocks = int(_np.frombuffer(appended, header, 1, off)[0])
                h = _np.frombuffer(appended, header, 3 + nblocks, off)
                sizes = h[3:]
                pos = off + hsize * (3 + nblocks)
                raw = b""
                for s in sizes:
                    raw += _zlib.decompress(appended[pos:pos + int(s)])
                    pos += int(s)
            else:
                n = int(_np.frombuffer(appended, header, 1, off)[0])
                raw = appended[off + hsize:off + hsize + n]
            arr = _np.frombuffer(raw, dtype).copy()
        else:
            arr = _np.array((el.text or "").split(), dtype=dtype)
        if name in ("connectivity", "offsets") and name in out:
            name = name + "_lines"  # the bond lines' cells after the vertices'
        out[name] = arr
    return out


class RunFolder:
    """A run folder written by `demlab run` or demlab.run: its summary, series and snapshots.

    summary: summary.json as a dict (a landmark the run did not measure is None, and
    summary["not_measured"] says why). Every CSV file a run writes, as a dict of numpy arrays
    keyed by column name (the names carry the units, e.g. t_s, fx_barrier_N_per_m): forces,
    front, energy, deposit, surface, peaks, barrier_pressure, envelope, release, lost, bonds_broken,
    track; DAN's blocks and front_synced. A file the run did not write raises
    FileNotFoundError, except track, which is {} for a run without tracers (output.track = []).
    snapshot_times: the instants of the snapshots, s; snapshot(i) reads one (negative i counts
    from the end), snapshot(t=...) the one nearest to a time, as a Snapshot.
    """

    def __init__(self, path):
        self.path = str(path)
        if not _os.path.isfile(_os.path.join(self.path, "scenario.toml")):
            raise InputError("%s: not a run folder (no scenario.toml)" % self.path)

    def _csv(self, name):
        return _read_csv(_os.path.join(self.path, name))

    @property
    def summary(self):
        """summary.json: the run's figures (run-out, run-up, peak times, ...) and their units"""
        with open(_os.path.join(self.path, "summary.json")) as f:
            return _json.load(f)

    @property
    def scenario_toml(self):
        """the resolved scenario the run used (scenario.toml), as a dict"""
        with open(_os.path.join(self.path, "scenario.toml"), "rb") as f:
            return _tomllib.load(f)

    forces = property(lambda self: self._csv("forces.csv"), doc="forces.csv: wall forces and impulses, N/m and N s/m")
    front = property(lambda self: self._csv("front.csv"), doc="front.csv: the front along the path, m")
    energy = property(lambda self: self._csv("energy.csv"), doc="energy.csv: the energy ledger, J/m")
    deposit = property(lambda self: self._csv("deposit.csv"), doc="deposit.csv: the deposit along the path, m")
    surface = property(lambda self: self._csv("surface.csv"),
                       doc="surface.csv: the deposit's surface over x above the bed (x_m, bed_m, surface_m, depth_m), m")
    lost = property(lambda self: self._csv("lost.csv"), doc="lost.csv: the discs that left the domain")
    peaks = property(lambda self: self._csv("peaks.csv"), doc="peaks.csv: along the path, the largest height, mean speed and bed pressure over the run")
    barrier_pressure = property(lambda self: self._csv("barrier_pressure.csv"),
                                doc="barrier_pressure.csv: the normal pressure along the barrier over time, Pa")
    envelope = property(lambda self: self._csv("envelope.csv"), doc="envelope.csv: the dam break's deposit surface, m")
    release = property(lambda self: self._csv("release.csv"), doc="release.csv: the settled release mass the run started from")
    bonds_broken = property(lambda self: self._csv("bonds_broken.csv"), doc="bonds_broken.csv: the cohesive bonds that broke")
    blocks = property(lambda self: self._csv("blocks.csv"), doc="blocks.csv: DAN's blocks at each snapshot")
    front_synced = property(lambda self: self._csv("front_synced.csv"),
                            doc="front_synced.csv: DAN's front shifted to the reference's arrival")

    @property
    def track(self):
        """track.csv: the tracer discs (output.track); {} for a run without tracers"""
        path = _os.path.join(self.path, "track.csv")
        if not _os.path.isfile(path) and not self.scenario_toml.get("output", {}).get("track"):
            return {}
        return self._csv("track.csv")

    def _snapshot_files(self):
        pvd = _os.path.join(self.path, "snapshots", "discs.pvd")
        if not _os.path.isfile(pvd):
            return []
        root = _ET.parse(pvd).getroot()
        out = []
        # the index is the run's own: a time that is not a finite number, or a file that is not
        # one of the folder's discs_*.vtp (a path elsewhere), is a damaged index (as `demlab render`)
        for d in root.iter("DataSet"):
            name = d.get("file") or ""
            try:
                t = float(d.get("timestep"))
            except (TypeError, ValueError):
                t = float("nan")
            if not _math.isfinite(t):
                raise InputError("%s: the snapshot time %r is not a finite number" % (pvd, d.get("timestep")))
            if not (name.startswith("discs_") and name.endswith(".vtp") and "/" not in name and "\\" not in name):
                raise InputError("%s: %r is not a snapshot file of this folder (discs_NNNNN.vtp)" % (pvd, name))
            out.append((t, _os.path.join(self.path, "snapshots", name)))
        return out

    @property
    def snapshot_times(self):
        """the snapshots' instants, s (numpy array)"""
        return _np.array([t for t, _ in self._snapshot_files()])

    def snapshot(self, i=None, t=None):
        """snapshot i (0 the first, -1 the last), or the one nearest to time t (s), as a Snapshot
        of numpy arrays"""
        files = self._snapshot_files()
        if not files:
            raise InputError("%s: no snapshots (output.snapshot_interval = 0?)" % self.path)
        if (i is None) == (t is None):
            raise InputError("snapshot(i=%r, t=%r): give the index i or the time t, one of them" % (i, t))
        if t is not None:
            i = int(_np.argmin(_np.abs(_np.array([tk for tk, _ in files]) - float(t))))
        t, f = files[i]
        a = read_vtp(f)
        time = float(a["TIME"][0]) if "TIME" in a else t
        return Snapshot(a, time)

    def __repr__(self):
        return "demlab.RunFolder(%r)" % self.path
