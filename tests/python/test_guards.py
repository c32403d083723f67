"""The Python module's guards (issue 54): World.step has the run loop's energy watch, a cut
series is an InputError naming file and line, and run(sc, None) uses runs/<name>."""
import math
import os
import shutil

import pytest

import demlab

# two undamped discs dropped 3 cm onto a floor (BlowUp.EnergyWatchCatchesStepsJustAboveTheCriticalOne)
TWO_DISCS = """
[rotation]
model = 1
[damping]
beta_n = 0.0
beta_s = 0.0
[timestep]
automatic = false
fixed = {dt}
[stop]
t_max = 2.0
rest_duration = 0.1
[output]
snapshot_interval = 0
[[discs]]
position = [0.0, 0.04]
radius = 0.01
[[discs]]
position = [0.1, 0.04]
radius = 0.01
[[walls]]
start = [-1.0, 0.0]
end = [1.0, 0.0]
"""


def two_discs(tmp_path, factor):
    m, k = 2672.0 * math.pi * 0.01 ** 2, 0.5e8  # disc and wall stiffness in series
    path = tmp_path / "two-discs.toml"
    path.write_text(TWO_DISCS.format(dt=repr(factor * 2.0 * math.sqrt(m / k))))
    return demlab.load_scenario(str(path))


def test_world_step_raises_run_error_on_energy_growth(tmp_path):
    # 1.3 times the contact's critical step: the CLI stops with "energy growth" (exit 3)
    w = demlab.World.from_scenario(two_discs(tmp_path, 1.3))
    with pytest.raises(demlab.RunError, match="energy growth"):
        w.step(200000)
    # half the critical step runs on
    w = demlab.World.from_scenario(two_discs(tmp_path, 0.5))
    w.step(20000)
    assert w.disc_count == 2


def test_a_cut_series_is_an_input_error_naming_file_and_line(cli_run, tmp_path):
    run = str(tmp_path / "run")
    shutil.copytree(cli_run, run)
    forces = os.path.join(run, "forces.csv")
    with open(forces) as f:
        text = f.read()
    lines = text.splitlines()
    with open(forces, "w") as f:  # the last row cut in its middle, without its line end
        f.write(text[: len(text) - 1 - len(lines[-1]) // 2])
    with pytest.raises(demlab.InputError, match=r"forces\.csv:%d: the last line has no line end" % len(lines)):
        demlab.RunFolder(run).forces
    with open(forces, "w") as f:  # a row with a cell missing
        f.write("\n".join(lines[:-1] + [",".join(lines[-1].split(",")[:-1])]) + "\n")
    with pytest.raises(demlab.InputError, match=r"forces\.csv:%d: .* cells, the header has" % len(lines)):
        demlab.RunFolder(run).forces
    assert len(demlab.RunFolder(cli_run).forces["t_s"]) == len(lines) - 1


def test_run_without_out_uses_runs_name(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    sc = demlab.load_scenario(_small_file(tmp_path))
    folder = demlab.run(sc, None, plots=False)
    assert not (tmp_path / "None").exists()
    assert (tmp_path / "runs" / sc.name / "summary.json").is_file()
    assert os.path.samefile(folder.path, tmp_path / "runs" / sc.name)
    with pytest.raises(demlab.InputError, match="output folder needs a name"):
        demlab.run(sc, "", plots=False)


def _small_file(tmp_path):
    path = tmp_path / "small.toml"
    path.write_text('[scenario]\nname = "small"\n[stop]\nt_max = 0.01\nrest_duration = 0.005\n[output]\nsnapshot_interval = 0\n'
                    "[[discs]]\nposition = [0.0, 0.02]\nradius = 0.01\n[[walls]]\nstart = [-1.0, 0.0]\nend = [1.0, 0.0]\n")
    return str(path)
