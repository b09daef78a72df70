# Experiments from Python: a run through the library's run lifecycle, and its folder read back.
import json
import os
import signal
import threading

import numpy as np
import pytest

import physgrad


def test_a_run_returns_its_summary_and_its_folder_reads_back(tmp_path):
    out = tmp_path / "toy"
    result = physgrad.run_experiment("scaled-toy", {"optimizers": ["gd", "newton"], "iters": 50,
                                                    "alpha": [1, 10]}, str(out))
    assert result["finished"]
    assert result["folder"] == str(out)
    runs = result["summary"]["runs"]
    assert {r["optimizer"] for r in runs} == {"gd", "newton"}
    assert len(runs) == 4  # two rules × two α
    # The dict is the folder's summary.json, and the metrics hold a row per run and iteration.
    assert physgrad.open_summary(str(out)) == result["summary"]
    metrics = physgrad.open_metrics(str(out))
    assert set(metrics["optimizer"]) == {"gd", "newton"}
    loss = metrics["loss"]
    assert isinstance(loss, np.ndarray) and loss.dtype == np.float64
    assert len(loss) == len(metrics["optimizer"]) > 4
    assert json.loads((out / "config.json").read_text())["experiment"] == "scaled-toy"


def test_bad_names_and_values_are_errors_naming_them(tmp_path):
    with pytest.raises(physgrad.Error, match="nosuch"):
        physgrad.run_experiment("nosuch", {}, str(tmp_path / "a"))
    with pytest.raises(physgrad.Error, match="fast"):
        physgrad.run_experiment("scaled-toy", {"lr": "fast"}, str(tmp_path / "b"))
    with pytest.raises(physgrad.Error, match="sgdd"):
        physgrad.run_experiment("scaled-toy", {"optimizers": ["gd", "sgdd"]}, str(tmp_path / "c"))
    assert not (tmp_path / "b").exists() and not (tmp_path / "c").exists()


def test_a_finished_folder_is_never_run_into_again(tmp_path):
    out = str(tmp_path / "done")
    physgrad.run_experiment("scaled-toy", {"optimizers": "newton", "iters": 20}, out)
    before = (tmp_path / "done" / "summary.json").read_bytes()
    with pytest.raises(physgrad.Error):
        physgrad.run_experiment("scaled-toy", {"optimizers": "gd", "iters": 20}, out)
    assert (tmp_path / "done" / "summary.json").read_bytes() == before


def test_progress_lines_reach_a_callable(tmp_path):
    lines = []
    result = physgrad.run_experiment("hig-toy", {"optimizers": "adam", "iters": 40,
                                                 "eval-every": 10, "lambda": 1},
                                     str(tmp_path / "p"), progress=lines.append)
    assert result["finished"]
    assert any(line.startswith("hig-toy: run 1/") for line in lines), lines
    assert all(isinstance(line, str) and "\n" not in line for line in lines)


def test_ctrl_c_stops_a_learning_run_in_order_and_resume_finishes_it(tmp_path):
    out = str(tmp_path / "stopped")
    # SIGINT from another thread, as a Ctrl-C arrives, while the run holds the process.
    timer = threading.Timer(0.5, lambda: os.kill(os.getpid(), signal.SIGINT))
    timer.start()
    try:
        with pytest.raises(KeyboardInterrupt, match="physgrad resume"):
            physgrad.run_experiment("hig-toy", {"optimizers": "adam", "time": 30,
                                                "eval-every": 20, "lambda": 1},
                                    out, progress=None)
    finally:
        timer.cancel()
    assert not (tmp_path / "stopped" / "summary.json").exists()
    assert (tmp_path / "stopped" / "checkpoint.pgc").exists()
    # A stop request does not outlive the run it stopped: the resumed run goes to its end.
    result = physgrad.resume_experiment(out, progress=None)
    assert result["finished"]
    assert result["summary"]["runs"][0]["optimizer"] == "adam"
