# The Python door under random attack (fuzz_door.py, in a process of its own so that a crash shows
# as one): 0 crashes, every attack ending in a clear error or an honest result — no exception of
# another type, no non-finite parameter, no half-applied step, no wrong "converged".
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest


@pytest.mark.parametrize("seed", [1, 2])
def test_random_attacks_hold(seed):
    done = subprocess.run([sys.executable, str(Path(__file__).with_name("fuzz_door.py")),
                           str(seed), "250"], capture_output=True, text=True, timeout=300,
                          env=dict(os.environ))
    assert done.returncode == 0, f"crashed ({done.returncode}): {done.stderr[-2000:]}"
    tally = json.loads(done.stdout)
    assert set(tally) == {"option containers", "wrong-rule options", "hostile numbers",
                          "non-finite steps", "C-level callables"}
    for kind, counts in tally.items():
        assert counts["attacks"] == 50 and counts["held"] == 50, (kind, counts["broke"][:5])
