# Ctrl-C (a real SIGINT) during a script's own experiment: the run stops in order, keeps its
# checkpoint, raises KeyboardInterrupt naming the folder and the Python call that resumes it, and
# that call continues to the final losses of an uninterrupted run. The signal arrives at a known
# step: the run layer's fault point stops the process there (SIGSTOP), the test sends SIGINT and
# then SIGCONT.
import os
import signal
import subprocess
import sys
import time

import pytest

SCRIPT = """
import sys
import numpy as np
import physgrad

class Square:
    name = "square"
    def forward(self, y):
        return y * np.abs(y)

def points(count, seed):
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2))
    return x, x

OWN = physgrad.LearningExperiment("own", "", Square(), [2, 8, 2], points, iterations=40,
                                  train_size=32, test_size=8,
                                  rules={"adam": {"lr": 0.01, "batch": 16},
                                         "hig": {"lr": 1.0, "batch": 16}})
try:
    if sys.argv[1] == "run":
        outcome = physgrad.run_experiment("own", {"checkpoint-every": 5}, sys.argv[2],
                                          progress=None, experiments=[OWN])
    else:
        outcome = physgrad.resume_experiment(sys.argv[2], progress=None, experiments=[OWN])
except KeyboardInterrupt as e:
    print("KeyboardInterrupt:", e)
    sys.exit(130)
for run in outcome.summary["runs"]:
    print(run["label"], repr(run["final"]["test_loss"]))
"""


def _child(tmp_path, *args, fault=None):
    script = tmp_path / "own.py"
    script.write_text(SCRIPT)
    env = dict(os.environ)
    env.pop("PHYSGRAD_FAULT", None)
    if fault:
        env["PHYSGRAD_FAULT"] = fault
    return subprocess.Popen([sys.executable, str(script), *args], cwd=tmp_path, env=env,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def _finish(process):
    out, err = process.communicate(timeout=300)
    return process.returncode, out, err


def _state(pid):
    with open(f"/proc/{pid}/stat") as f:
        return f.read().rsplit(")", 1)[1].split()[0]


def _interrupt_when_stopped(process):
    deadline = time.monotonic() + 120
    while _state(process.pid) != "T":
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "the run never reached its fault point"
        time.sleep(0.02)
    os.kill(process.pid, signal.SIGINT)
    os.kill(process.pid, signal.SIGCONT)


@pytest.mark.parametrize("point", ["claimed:1", "checkpoint:3", "checkpoint:11"])
def test_ctrl_c_keeps_the_run_and_its_resume_ends_as_an_uninterrupted_one(tmp_path, point):
    status, whole, err = _finish(_child(tmp_path, "run", "whole"))
    assert status == 0, err
    assert whole.count("final") == 0 and len(whole.splitlines()) == 2, whole

    process = _child(tmp_path, "run", "part", fault="stop@" + point)
    _interrupt_when_stopped(process)
    status, out, err = _finish(process)
    assert status == 130, (status, out, err)
    [line] = [l for l in out.splitlines() if l.startswith("KeyboardInterrupt:")]
    assert "part" in line and "checkpoint kept" in line, line
    assert "physgrad.resume_experiment(" in line, line
    assert "physgrad resume " not in line, line
    assert (tmp_path / "part" / "checkpoint.pgc").exists()
    assert not (tmp_path / "part" / "summary.json").exists()

    status, resumed, err = _finish(_child(tmp_path, "resume", "part"))
    assert status == 0, err
    assert resumed == whole
