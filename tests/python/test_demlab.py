"""The Python module against the executable: the same checks, the same bytes, the same state."""
import filecmp
import json
import os
import signal
import subprocess

import numpy as np
import pytest

import demlab
from conftest import EXE, SCENARIO, SMALL, SMALL_SET


def test_load_scenario_applies_overrides_and_writes_the_resolved_toml():
    sc = demlab.load_scenario(SCENARIO, {"release.scale": 20, "release.variant": "I", "output.track": [0, 5]})
    assert sc.name == "geometry-A"
    assert sc["release.scale"] == 20
    assert sc["release.variant"] == "I"
    assert sc["output.track"] == [0, 5]
    assert sc["material.friction_disc_deg"] == pytest.approx(15.5)
    text = sc.to_toml()
    assert "scale = 20" in text and 'variant = "I"' in text
    assert len(sc.keys()) > 100 and "damping.dp_mode" in sc.keys()
    # a changed copy, checked again; the original is unchanged
    sc2 = sc.with_overrides({"rotation.model": 1})
    assert sc2["rotation.model"] == 1 and sc["rotation.model"] == 3


@pytest.mark.parametrize("key,value,fragment", [
    ("material.friction_disc_deg", 120, "must be in [0.0, 89.0]"),
    ("material.frction_disc_deg", 12, "did you mean 'material.friction_disc_deg'"),
    ("release.variant", "III", "release.variant"),
    ("release.scale", "four", "release.scale"),
])
def test_input_error_carries_the_key_and_the_cli_message(tmp_path, key, value, fragment):
    with pytest.raises(demlab.InputError) as err:
        demlab.load_scenario(SCENARIO, {key: value})
    assert err.value.key == key
    assert fragment in str(err.value)
    assert isinstance(err.value, ValueError)
    # the executable refuses the same value with the same message (in its own terms: --set
    # 'key=value' where Python says overrides['key']) and exit code 2
    literal = '"%s"' % value if isinstance(value, str) else str(value)
    p = subprocess.run([EXE, "run", SCENARIO, "--out", str(tmp_path / "x"), "--set", "%s=%s" % (key, literal)],
                       capture_output=True, text=True)
    assert p.returncode == 2
    assert str(err.value).split(": ", 1)[1] in p.stderr
    assert not (tmp_path / "x").exists()


def test_a_missing_scenario_file_is_an_input_error(tmp_path):
    with pytest.raises(demlab.InputError):
        demlab.load_scenario(str(tmp_path / "none.toml"))


def test_run_from_python_writes_the_same_bytes_as_the_cli(cli_run, tmp_path):
    seen = []
    folder = demlab.run(demlab.load_scenario(SCENARIO, SMALL), tmp_path / "py", threads=2, plots=False,
                        progress=lambda t, t_max, rate: seen.append((t, t_max, rate)))
    assert isinstance(folder, demlab.RunFolder)
    names = sorted(os.listdir(cli_run))
    assert names == sorted(os.listdir(folder.path))
    for name in names:
        if name in ("summary.json", "snapshots"):
            continue
        assert filecmp.cmp(os.path.join(cli_run, name), os.path.join(folder.path, name), shallow=False), name
    snaps = sorted(os.listdir(os.path.join(cli_run, "snapshots")))
    assert len(snaps) > 4
    match, mismatch, errors = filecmp.cmpfiles(os.path.join(cli_run, "snapshots"),
                                               os.path.join(folder.path, "snapshots"), snaps, shallow=False)
    assert mismatch == [] and errors == []
    # the summary: the same figures, only the wall-clock ones differ
    a, b = json.load(open(os.path.join(cli_run, "summary.json"))), folder.summary
    clock = {"wall_seconds", "particle_steps_per_second", "release_wall_seconds", "broadphase_update_seconds",
             "force_pass_busy_share", "force_pass_busy_fallbacks", "force_pass_one_range_cuts"}
    assert {k: v for k, v in a.items() if k not in clock} == {k: v for k, v in b.items() if k not in clock}
    # progress: (t, t_max, steps/s), the last call at the end of the run
    assert seen and all(s[1] == pytest.approx(0.3) for s in seen)
    assert [s[0] for s in seen] == sorted(s[0] for s in seen)
    assert seen[-1][0] == pytest.approx(b["t_end"]) and seen[-1][2] > 0


def test_run_refuses_an_existing_folder_unless_forced(cli_run):
    with pytest.raises(demlab.InputError, match="exists already"):
        demlab.run(SCENARIO, cli_run)


def test_run_folder_series_are_numpy_arrays_keyed_by_column(cli_run):
    f = demlab.RunFolder(cli_run)
    s = f.summary
    assert s["n_discs"] == 364 and s["units"]["runout_s"] == "m"
    forces = f.forces
    n = len(forces["t_s"])
    assert n == round(s["t_end"] / 0.005) + 1
    for col in ("fx_barrier_N_per_m", "fy_arc_N_per_m", "ix_total_Ns_per_m", "fx_gate_N_per_m",
                "fx_barrier_filtered_N_per_m", "fy_arc_filtered_N_per_m"):
        assert forces[col].shape == (n,) and forces[col].dtype == np.float64, col
    # the filtered loads are not measured before the first whole window: NaN, not text
    assert np.isnan(forces["fx_barrier_filtered_N_per_m"][0])
    # the gate holds the mass at t = 0: the slope carries the weight's share along it
    assert forces["fy_slope_N_per_m"][0] < 0
    assert f.energy["t_s"].shape == (n,)
    assert len(f.front["t_s"]) == n
    assert "s_m" in f.deposit or len(f.deposit) > 1
    assert f.scenario_toml["release"]["scale"] == 20
    assert f.track == {}  # no tracers were asked for
    with pytest.raises(FileNotFoundError):
        f.bonds_broken  # no bonds: no such file


def test_every_file_a_run_writes_has_an_accessor(cli_run):
    """issue 55, row 7: peaks, barrier pressure and the release mass too; release.csv's
    generation figures (# lines) do not hide its table"""
    f = demlab.RunFolder(cli_run)
    accessors = {"forces.csv": "forces", "front.csv": "front", "energy.csv": "energy", "deposit.csv": "deposit",
                 "surface.csv": "surface",
                 "peaks.csv": "peaks", "barrier_pressure.csv": "barrier_pressure", "release.csv": "release",
                 "lost.csv": "lost", "envelope.csv": "envelope", "track.csv": "track",
                 "bonds_broken.csv": "bonds_broken", "blocks.csv": "blocks", "front_synced.csv": "front_synced"}
    written = [n for n in os.listdir(cli_run) if n.endswith(".csv")]
    assert {"peaks.csv", "barrier_pressure.csv", "release.csv"} <= set(written)
    for name in written:
        assert name in accessors, name
        table = getattr(f, accessors[name])
        assert isinstance(table, dict) and table, name
    assert len(f.release["r_m"]) == f.summary["n_discs"]
    assert "max_bed_pressure_Pa" in f.peaks


def test_a_landmark_not_measured_is_none_with_its_reason(cli_run):
    """issue 55, row 3: at 0.3 s the front is on the slope"""
    s = demlab.RunFolder(cli_run).summary
    assert s["t_front_at_barrier"] is None and s["peak_fx_barrier"] is None
    assert "did not reach the barrier" in s["not_measured"]["t_front_at_barrier"]
    assert s["runout_s"] is not None


def test_snapshot_by_time_is_the_nearest(cli_run):
    f = demlab.RunFolder(cli_run)
    times = f.snapshot_times
    assert f.snapshot(t=times[2] + 0.004).time == pytest.approx(times[2])
    assert f.snapshot(t=1e9).time == pytest.approx(times[-1])
    with pytest.raises(demlab.InputError, match="one of them"):
        f.snapshot(1, t=0.1)


def test_scenario_keys_answer_in_and_errors_speak_python(tmp_path):
    sc = demlab.load_scenario(SCENARIO, SMALL)
    assert "release.scale" in sc and "release.scal" not in sc and 3 not in sc
    assert list(sc) == demlab.key_names()
    with pytest.raises(demlab.InputError, match=r"scenario\['material.frction_disc_deg'\].*did you mean 'material.friction_disc_deg'") as e:
        sc["material.frction_disc_deg"]
    assert e.value.key == "material.frction_disc_deg"
    with pytest.raises(demlab.InputError, match=r"overrides\['release.scal'\]") as e:
        demlab.load_scenario(SCENARIO, {"release.scal": 3})
    assert "--set" not in str(e.value) and e.value.key == "release.scal"
    out = tmp_path / "taken"
    out.mkdir()
    (out / "mine.txt").write_text("a user's file")
    with pytest.raises(demlab.InputError) as e:
        demlab.run(sc, str(out))
    assert "--out" not in str(e.value) and "--force" not in str(e.value)


def test_snapshots_have_the_right_shapes_and_units(cli_run):
    f = demlab.RunFolder(cli_run)
    times = f.snapshot_times
    assert times[0] == 0.0 and np.all(np.diff(times) > 0)
    first, last = f.snapshot(0), f.snapshot(-1)
    assert last.time == pytest.approx(f.summary["t_end"])
    for snap in (first, last):
        n = len(snap)
        assert n == 364
        assert snap.positions.shape == (n, 2) and snap.velocities.shape == (n, 2)
        for a in (snap.radii, snap.speeds, snap.angles, snap.omegas, snap.layers, snap.ids):
            assert a.shape == (n,)
        # radii in m: [0.25, 0.5] mm times the scale 20, shrunk by 3 %
        assert snap.radii.min() >= 0.97 * 0.005 - 1e-12 and snap.radii.max() <= 0.97 * 0.01 + 1e-12
        np.testing.assert_allclose(np.hypot(*snap.velocities.T), snap.speeds, rtol=1e-8, atol=1e-12)
        assert sorted(snap.ids) == list(range(n))
    assert np.all(first.speeds == 0.0)
    # the release box lies on the slope behind the gate at x = 0.5276 m
    assert first.positions[:, 0].max() < 0.5276


def test_world_steps_to_the_cli_state_after_1000_steps(tmp_path):
    out = str(tmp_path / "cli1000")
    subprocess.run([EXE, "run", SCENARIO, "--out", out, "--no-plots", *SMALL_SET, "--set", "stop.max_steps=1000"],
                   check=True, stdout=subprocess.DEVNULL)
    folder = demlab.RunFolder(out)
    assert folder.summary["steps"] == 1000 and folder.summary["stop_reason"] == "max_steps"
    snap = folder.snapshot(-1)
    w = demlab.World.from_scenario(demlab.load_scenario(SCENARIO, SMALL))
    w.step(400)
    w.step(600)
    assert w.step_count == 1000
    assert w.time == pytest.approx(folder.summary["t_end"], rel=1e-9)  # the summary keeps 10 digits
    order, snap_order = np.argsort(w.ids), np.argsort(snap.ids)
    # the binary snapshots keep every double as it is: the same bits
    np.testing.assert_array_equal(w.positions[order], snap.positions[snap_order])
    np.testing.assert_array_equal(w.velocities[order], snap.velocities[snap_order])
    np.testing.assert_array_equal(w.omegas[order], snap.omegas[snap_order])
    np.testing.assert_array_equal(w.angles[order], snap.angles[snap_order])
    np.testing.assert_array_equal(w.radii[order], snap.radii[snap_order])


def test_ascii_snapshots_read_as_the_binary_ones(tmp_path):
    runs = {}
    for fmt in ("binary", "ascii"):
        out = str(tmp_path / fmt)
        subprocess.run([EXE, "run", SCENARIO, "--out", out, "--no-plots", *SMALL_SET, "--set", "stop.t_max=0.25",
                        "--set", 'output.snapshot_format="%s"' % fmt], check=True, stdout=subprocess.DEVNULL)
        runs[fmt] = demlab.RunFolder(out)
    a, b = runs["binary"].snapshot(-1), runs["ascii"].snapshot(-1)
    assert a.time == b.time
    np.testing.assert_allclose(a.positions, b.positions, rtol=1e-11, atol=0)
    np.testing.assert_allclose(a.velocities, b.velocities, rtol=1e-8, atol=1e-12)
    np.testing.assert_array_equal(a.ids, b.ids)
    np.testing.assert_array_equal(a.layers, b.layers)


def test_views_kept_across_a_lost_disc_read_live_memory(tmp_path):
    # a disc leaves the domain and is taken out: the arrays close up in their own buffers, so a
    # view read before holds the new rows first (it read freed memory when they were moved)
    sc = tmp_path / "fall.toml"
    sc.write_text("[world]\ndomain = [[-1.0, -0.2], [1.0, 1.0]]\n[stop]\nt_max = 1.0\nrest_duration = 0.1\n"
                  "[[discs]]\nposition = [0.0, 0.5]\nradius = 0.01\n"
                  "[[discs]]\nposition = [0.5, 0.5]\nradius = 0.01\n"
                  "[[discs]]\nposition = [-0.5, 0.5]\nradius = 0.01\n"
                  "[[walls]]\nstart = [-0.7, 0.0]\nend = [0.2, 0.0]\n")
    w = demlab.World.from_scenario(demlab.load_scenario(str(sc)))
    p, ids = w.positions, w.ids
    assert w.disc_count == 3
    while w.disc_count == 3 and w.time < 1.0:
        w.step(100)
    assert w.disc_count == 2, "the disc beside the wall's end falls out of the domain"
    assert np.shares_memory(w.positions, p)
    np.testing.assert_array_equal(p[:2], w.positions)
    np.testing.assert_array_equal(ids[:2], w.ids)
    assert list(w.ids) == [0, 2]


def test_arguments_are_checked_before_any_output(tmp_path):
    sc = demlab.load_scenario(SCENARIO, SMALL)
    out = tmp_path / "o"
    for kw in ({"checkpoint_every": -5}, {"checkpoint_every": float("nan")}, {"checkpoint_every": float("inf")},
               {"progress": 5}):
        with pytest.raises(demlab.InputError):
            demlab.run(sc, str(out), **kw)
        assert not out.exists(), kw
    with pytest.raises(demlab.InputError):
        demlab.run(sc, str(tmp_path / "nul\0tail"))
    with pytest.raises(demlab.InputError):
        demlab.load_scenario(SCENARIO + "\0junk")
    with pytest.raises(demlab.InputError):
        demlab.load_scenario(SCENARIO, release_from=str(tmp_path / "r\0x"))
    assert not (tmp_path / "nul").exists()
    for threads in (0, -1, 65):
        with pytest.raises(demlab.InputError):
            demlab.World.from_scenario(sc, threads=threads)
    # an integer beyond TOML's 64 bits: an InputError with its key, not a bare RuntimeError
    for key, value in (("scenario.seed", 2 ** 63), ("stop.t_max", 10 ** 30), ("scenario.seed", np.uint64(2 ** 64 - 1))):
        with pytest.raises(demlab.InputError) as e:
            demlab.load_scenario(SCENARIO, {key: value})
        assert e.value.key == key and "64-bit" in str(e.value)
    # a value out of its range, in Python's terms
    with pytest.raises(demlab.InputError) as e:
        demlab.load_scenario(SCENARIO, {"stop.t_max": -1})
    assert str(e.value).startswith("overrides['stop.t_max'] = -1 s: must be in"), str(e.value)
    # the executable's option names become Python's, but not inside a path
    mine = tmp_path / "x--out"
    mine.mkdir()
    with pytest.raises(demlab.InputError) as e:
        demlab.run(sc, str(mine))
    assert str(mine) in str(e.value) and "force=True" in str(e.value)


def test_a_damaged_snapshot_index_is_an_input_error(cli_run, tmp_path):
    # as `demlab render`: a time that is not a number, or a file outside the folder
    import shutil
    copy = tmp_path / "run"
    shutil.copytree(cli_run, copy)
    pvd = copy / "snapshots" / "discs.pvd"
    text = pvd.read_text()
    assert 'timestep="0" file="discs_00000.vtp"' in text
    for bad in ('timestep="nan" file="discs_00000.vtp"', 'timestep="0" file="../../other/discs_00000.vtp"'):
        pvd.write_text(text.replace('timestep="0" file="discs_00000.vtp"', bad))
        with pytest.raises(demlab.InputError):
            demlab.RunFolder(str(copy)).snapshot_times


def test_world_arrays_are_read_only_views_with_units():
    w = demlab.World.from_scenario(demlab.load_scenario(SCENARIO, SMALL), threads=2)
    n = w.disc_count
    assert n == 364 and w.time == 0.0 and w.step_count == 0 and 0 < w.dt < 1e-4
    p = w.positions
    assert p.shape == (n, 2) and p.dtype == np.float64 and not p.flags.writeable
    with pytest.raises(ValueError):
        p[0, 0] = 1.0
    assert w.velocities.shape == (n, 2) and w.radii.shape == (n,) and w.omegas.shape == (n,)
    # a view, not a copy: two reads share the world's memory, and it moves with the world
    assert np.shares_memory(w.positions, p)
    y0 = p[:, 1].copy()
    w.step(2000)
    assert p[:, 1].mean() < y0.mean() - 1e-5  # the mass has started to fall
    # kinetic energy from the arrays as the world sums it, J/m
    ke = 0.5 * np.sum(w.masses * np.sum(w.velocities ** 2, axis=1))
    e = w.energy()
    assert e["kinetic_translation"] == pytest.approx(ke, rel=1e-9)
    assert set(e) >= {"potential", "elastic", "dissipated_contacts", "work_by_walls", "balance"}
    f = w.wall_forces()
    assert f.shape == (w.wall_count, 2)
    # the discs press on the slope W1 (down and along it)
    assert f[0, 1] < 0
    assert w.wall_active(3)  # the gate is still rising
    with pytest.raises(demlab.InputError):
        w.wall_active(99)
    with pytest.raises(demlab.InputError):
        w.step(-1)


def test_world_of_the_continuum_model_is_refused():
    with pytest.raises(demlab.InputError, match="dem"):
        demlab.World.from_scenario(demlab.load_scenario(SCENARIO, {"scenario.solver": "dan"}))


def test_ctrl_c_in_python_writes_a_checkpoint_and_the_resumed_run_is_the_same(cli_run, tmp_path):
    out = tmp_path / "interrupted"
    state = {"sent": False}

    def progress(t, t_max, rate):
        # the first call comes at once, while the run runs: the interrupt lands mid-run on any
        # machine (a condition on t raced the 0.25 s between calls on a fast one)
        if not state["sent"]:
            state["sent"] = True
            os.kill(os.getpid(), signal.SIGINT)

    with pytest.raises(demlab.Interrupted) as err:
        demlab.run(demlab.load_scenario(SCENARIO, SMALL), out, plots=False, progress=progress)
    assert isinstance(err.value, KeyboardInterrupt)
    assert "demlab resume" in str(err.value)
    assert (out / "checkpoint.bin").exists() and not (out / "summary.json").exists()
    subprocess.run([EXE, "resume", str(out)], check=True, stdout=subprocess.DEVNULL)
    for name in ("forces.csv", "front.csv", "energy.csv", "deposit.csv", "scenario.toml"):
        assert filecmp.cmp(os.path.join(cli_run, name), out / name, shallow=False), name


def test_help_documents_every_public_name():
    assert "demlab.run" in demlab.__doc__ or "demlab.load_scenario" in demlab.__doc__
    for name in demlab.__all__:
        obj = getattr(demlab, name)
        assert obj.__doc__, name
    for name in ("step", "wall_forces", "energy", "from_scenario"):
        assert getattr(demlab.World, name).__doc__, name
    for name in ("summary", "forces", "snapshot", "snapshot_times"):
        assert getattr(demlab.RunFolder, name).__doc__, name


def test_release_from_is_the_working_directorys_as_the_cli(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sc = demlab.load_scenario(SCENARIO, SMALL, release_from="masses/release.csv")
    assert sc["release.from_file"] == str(tmp_path / "masses/release.csv")
