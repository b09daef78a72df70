# Experiments from Python: a run through the library's run lifecycle, and its folder read back.
import json

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
