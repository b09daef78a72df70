# A script's own learning experiment (physgrad.LearningExperiment) through the run lifecycle:
# its run folder, a resume that needs it given again, the index, and its mistakes named.
import numpy as np
import pytest

import physgrad


class Square:
    name = "square"

    def forward(self, y):
        return y * np.abs(y)


def points(count, seed):
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2))
    return x, x


def experiment(name="own", data=points, simulator=None, **kw):
    return physgrad.LearningExperiment(name, "a test experiment", simulator or Square(), [2, 8, 2],
                                       data, iterations=20, train_size=32, test_size=8, **kw)


def test_its_run_fills_a_folder_and_the_index_lists_it(tmp_path):
    own = experiment(rules={"adam": {"lr": 0.01, "batch": 16}})
    result = physgrad.run_experiment("own", {"optimizers": "adam"}, str(tmp_path / "a"),
                                     progress=None, experiments=[own])
    assert result.finished
    [run] = result.summary["runs"]
    assert run["optimizer"] == "adam" and run["params"]["lr"] == 0.01
    assert len(physgrad.open_metrics(result.folder)["test_loss"]) > 1
    index = physgrad.write_index(str(tmp_path), experiments=[own])
    assert index["folders"] == 1
    assert 'href="./a/report.html"' in open(index["page"]).read()
    # The reference experiments stay beside it.
    assert physgrad.run_experiment("scaled-toy", {"iters": 2}, str(tmp_path / "b"), progress=None,
                                   experiments=[own]).finished


def test_resume_needs_the_experiment_given_again(tmp_path):
    folder = tmp_path / "part"
    folder.mkdir()
    (folder / "config.json").write_text('{"experiment": "own", "settings": {}}')
    with pytest.raises(physgrad.Error, match="unknown experiment 'own'"):
        physgrad.resume_experiment(str(folder), progress=None)
    assert physgrad.resume_experiment(str(folder), progress=None,
                                      experiments=[experiment()]).finished


def test_mistakes_are_errors_naming_them(tmp_path):
    with pytest.raises(physgrad.Error, match="two experiments are named 'poisson'"):
        physgrad.run_experiment("poisson", {}, str(tmp_path / "a"),
                                experiments=[experiment("poisson")])
    with pytest.raises(physgrad.Error, match="is not a list of physgrad.LearningExperiment"):
        physgrad.run_experiment("own", {}, str(tmp_path / "b"), experiments=["own"])
    with pytest.raises(physgrad.Error, match="widths needs at least two layers"):
        physgrad.LearningExperiment("w", "", Square(), [2], points)
    with pytest.raises(physgrad.Error, match="data is not callable"):
        physgrad.LearningExperiment("d", "", Square(), [2, 2], 3)
    with pytest.raises(physgrad.Error, match=r"rules\[hig\] is not a dict"):
        physgrad.LearningExperiment("r", "", Square(), [2, 2], points, rules={"hig": 1.0})
    with pytest.raises(physgrad.Error, match="lr"):
        physgrad.run_experiment("own", {"optimizers": "adam"}, str(tmp_path / "l"), progress=None,
                                experiments=[experiment(rules={"adam": {"lr": "x"}})])
    wrong = experiment(data=lambda count, seed: (np.zeros((count, 3)), np.zeros((count, 2))))
    with pytest.raises(physgrad.Error, match=r"inputs \(32, 3\).*expected \(32, 2\)"):
        physgrad.run_experiment("own", {}, str(tmp_path / "c"), progress=None,
                                experiments=[wrong])
    assert not (tmp_path / "c").exists()


def test_an_exception_in_a_callback_is_raised_again_naming_the_experiment(tmp_path):
    class Broken(Square):
        def forward(self, y):
            if y.ndim == 1 and abs(y[0]) > 0:  # not the size probe at construction (y = 0)
                raise KeyError("no physics here")
            return super().forward(y)

    with pytest.raises(KeyError, match="no physics here.*experiment own"):
        physgrad.run_experiment("own", {"optimizers": "adam"}, str(tmp_path / "a"),
                                progress=None, experiments=[experiment(simulator=Broken())])
