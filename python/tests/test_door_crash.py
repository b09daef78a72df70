# Arguments that once crashed the interpreter (SIGSEGV): each runs in a fresh interpreter, which
# must end with physgrad.Error naming the mistake (exit status 1), not with a signal.
import os
import subprocess
import sys

import pytest

CALLS = [
    "physgrad.write_index('.', experiments=[None])",
    "physgrad.write_index('.', experiments=(None,))",
    "physgrad.run_experiment('scaled-toy', {}, 'out', progress=None, experiments=[None])",
    "physgrad.resume_experiment('nowhere', progress=None, experiments=(None,))",
    "physgrad.write_index('.', experiments=[own, None])",
    "physgrad.write_index('.', experiments=[own, 5])",
]

SETUP = """
import numpy as np
import physgrad
class Same:
    def forward(self, y):
        return y
own = physgrad.LearningExperiment('own', '', Same(), [2, 2],
                                  lambda count, seed: (np.zeros((count, 2)),) * 2)
"""


@pytest.mark.parametrize("call", CALLS)
def test_a_wrong_experiments_list_is_an_error_not_a_crash(tmp_path, call):
    done = subprocess.run([sys.executable, "-c", SETUP + call], cwd=tmp_path,
                          capture_output=True, text=True, env=dict(os.environ), timeout=120)
    assert done.returncode == 1, (done.returncode, done.stderr[-2000:])
    last = done.stderr.strip().splitlines()[-1]
    assert last.startswith("physgrad.Error: experiments: ") or "physgrad.Error" in last, last
    assert "is not a list of physgrad.LearningExperiment" in last, last
    assert not (tmp_path / "out").exists()
