# From Python, slow BLAS kernels are not silent: importing physgrad warns once with
# blas_core_note() when OpenBLAS runs kernels slower than the CPU can (OPENBLAS_CORETYPE unset on
# a CPU newer than the OpenBLAS build), and not at all when it does not.
import os
import subprocess
import sys

import pytest

SCRIPT = """
import warnings
with warnings.catch_warnings(record=True) as caught:
    warnings.simplefilter("always")
    import physgrad
    import physgrad.torch
    import importlib
    importlib.import_module("physgrad")
print(repr(physgrad.blas_core_note()))
for w in caught:
    print(w.category.__name__, "|", w.message)
"""


@pytest.mark.parametrize("core", [None, "Haswell"])
def test_import_warns_once_with_the_blas_note(core):
    env = dict(os.environ)
    env.pop("OPENBLAS_CORETYPE", None)
    if core:
        env["OPENBLAS_CORETYPE"] = core
    done = subprocess.run([sys.executable, "-c", SCRIPT], env=env, capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 0, done.stderr
    note, *warned = done.stdout.splitlines()
    note = eval(note)
    blas = [line for line in warned if line.startswith("BlasCoreWarning | ")]
    assert blas == ([f"BlasCoreWarning | {note}"] if note else [])
    assert "OPENBLAS_CORETYPE" not in env or env["OPENBLAS_CORETYPE"] == core
