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
