# The install: setup.py refuses a configured build tree whose Python has another ABI (its module
# would go in under the wrong tag), and docs/python.md names the interpreter that makes the venv.
import importlib.util
import os
import pathlib
import sys
import sysconfig

import pytest

SOURCE = pathlib.Path(__file__).resolve().parents[2]


def _setup_module():
    spec = importlib.util.spec_from_file_location("physgrad_setup", SOURCE / "setup.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)  # not __main__: setup() is not called
    return module


def _tree(tmp_path, python):
    (tmp_path / "CMakeCache.txt").write_text(f"CMAKE_BUILD_TYPE:STRING=Release\n"
                                            f"Python3_EXECUTABLE:FILEPATH={python}\n")
    return tmp_path


def test_a_tree_for_another_interpreter_is_refused(tmp_path):
    setup = _setup_module()
    other = tmp_path / "python3.99"
    other.write_text("#!/bin/sh\necho .cpython-399-x86_64-linux-gnu.so\n")
    other.chmod(0o755)
    tree = _tree(tmp_path, other)
    with pytest.raises(RuntimeError, match=f"configured for {other} .*not for") as raised:
        setup.check_build_tree(tree)
    assert "\n" not in str(raised.value)
    setup.check_build_tree(_tree(tmp_path, sys.executable))  # this interpreter's: taken
    with pytest.raises(RuntimeError, match="no CMakeCache.txt"):
        setup.check_build_tree(tmp_path / "nowhere")
    assert setup.interpreter_suffix(sys.executable) == sysconfig.get_config_var("EXT_SUFFIX")


def test_the_install_commands_name_the_interpreter():
    text = (SOURCE / "docs" / "python.md").read_text()
    commands = [line for line in text.splitlines() if "-m venv" in line and
                not line.startswith(("`", " "))]
    assert commands, "docs/python.md shows how to make the venv"
    for line in commands:
        assert line.startswith("/usr/bin/python3 -m venv"), line
    assert "pip install -v " in text
