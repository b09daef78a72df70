# Options are never silently ignored: the torch optimizers honour κ and check their param groups
# at every step, and a LearningExperiment refuses unknown rules, bad rule options and a resume
# whose definition changed, all with one-line errors naming the value.
import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt


def _problem():
    torch.manual_seed(0)
    model = torch.nn.Sequential(torch.nn.Linear(2, 4), torch.nn.Tanh(),
                                torch.nn.Linear(4, 3)).double()
    inputs = torch.linspace(-1, 1, 20, dtype=torch.float64).reshape(10, 2)
    targets = torch.sin(torch.arange(30, dtype=torch.float64)).reshape(10, 3)
    simulate = lambda x: torch.stack([x[:, 0], 10 * x[:, 1], x[:, 2] ** 2], 1)  # noqa: E731
    loss = lambda y, t: 0.5 * ((y - t) ** 2).sum(1).mean()  # noqa: E731
    return model, pt.jacobian_closure(model, simulate, loss, inputs, targets)


@pytest.mark.parametrize("rule, kappa", [(pt.HIG, 0.25), (pt.GN, 0.5), (pt.HIG, 1.0)])
def test_kappa_is_the_step_of_jacobian_step_with_that_kappa(rule, kappa):
    model, closure = _problem()
    _, j, g = closure()
    delta, _ = physgrad.jacobian_step(j.numpy(), g.reshape(-1).numpy(), lr=0.5, kappa=kappa)
    default, _ = physgrad.jacobian_step(j.numpy(), g.reshape(-1).numpy(), lr=0.5,
                                        kappa=0.5 if rule is pt.HIG else 1.0)
    assert not np.allclose(delta, default)
    before = torch.cat([p.detach().reshape(-1) for p in model.parameters()])
    rule(model.parameters(), lr=0.5, kappa=kappa).step(closure)
    after = torch.cat([p.detach().reshape(-1) for p in model.parameters()])
    torch.testing.assert_close(after - before, torch.from_numpy(delta), rtol=1e-10, atol=1e-14)


@pytest.mark.parametrize("key, value, match", [("lr", -1, "lr"), ("rcond", 5.0, "rcond"),
                                               ("lr", "fast", "lr"), ("kappa", float("nan"), "kappa")])
def test_a_group_changed_after_construction_is_refused_at_the_step(key, value, match):
    model, closure = _problem()
    opt = pt.HIG(model.parameters(), lr=0.5)
    opt.param_groups[0][key] = value
    before = [p.detach().clone() for p in model.parameters()]
    with pytest.raises(physgrad.Error, match=match) as raised:
        opt.step(closure)
    assert "\n" not in str(raised.value)
    assert all(torch.equal(p, b) for p, b in zip(model.parameters(), before))


def test_complex_parameters_are_refused():
    p = torch.nn.Parameter(torch.zeros(2, dtype=torch.complex128))
    with pytest.raises(physgrad.Error, match="complex"):
        pt.HIG([p])
    with pytest.raises(physgrad.Error, match="complex"):
        pt.GN([torch.nn.Parameter(torch.zeros(2))]).add_param_group({"params": [p]})


class Square:
    name = "square"

    def forward(self, y):
        return y * np.abs(y)


def points(count, seed):
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2))
    return x, x


def _experiment(name="own", widths=(2, 8, 2), data=points, simulator=None, **kw):
    return physgrad.LearningExperiment(name, "", simulator or Square(), list(widths), data,
                                       iterations=20, train_size=32, test_size=8, **kw)


@pytest.mark.parametrize("rules, match", [
    ({"hgi": {"lr": 1.0}}, r"rules: unknown rule 'hgi'.*hig"),
    ({5: {"lr": 1.0}}, r"rules key 5 is not a rule's name.*adam"),
    ({"hig": {"lr": -1.0}}, r"rules\[hig\]: .*lr"),
    ({"hig": {"lrr": 1.0}}, r"rules\[hig\]: .*lrr"),
    ({"adam": {"batch": 0}}, r"rules\[adam\]: batch"),
])
def test_rules_are_checked_when_the_experiment_is_made(rules, match):
    with pytest.raises(physgrad.Error, match=match) as raised:
        _experiment(rules=rules)
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize("name", ["../outside", "a/b", "..", "x..y"])
def test_a_name_that_is_a_path_is_refused(name):
    with pytest.raises(physgrad.Error, match="name"):
        _experiment(name=name)


def _cube(y):
    return y ** 3


class Cube(Square):
    name = "cube"

    def forward(self, y):
        return _cube(y)


def other_points(count, seed):
    x, _ = points(count, seed)
    return x, 0.5 * x


@pytest.mark.parametrize("changed, match", [
    (dict(rules={"adam": {"lr": 0.02}}), r"rules\[adam\]"),
    (dict(rules={"adam": {"lr": 0.01, "batch": 8}}), r"rules\[adam\]"),
    (dict(simulator=Cube()), "simulator"),
    (dict(data=other_points), "data"),
    (dict(widths=(2, 4, 2)), "widths"),
])
def test_a_resume_with_a_changed_definition_is_refused(tmp_path, changed, match):
    start = dict(rules={"adam": {"lr": 0.01}})
    folder = tmp_path / "part"
    folder.mkdir()
    physgrad.run_experiment("own", {"optimizers": "adam", "iters": 5}, str(folder / "whole"),
                            progress=None, experiments=[_experiment(**start)])
    # A run that was stopped before it started: its config.json alone, as Run::start wrote it.
    (folder / "whole" / "summary.json").unlink()
    config = (folder / "whole" / "config.json").read_text()
    stopped = tmp_path / "stopped"
    stopped.mkdir()
    (stopped / "config.json").write_text(config)
    with pytest.raises(physgrad.Error, match="definition changed.*" + match) as raised:
        physgrad.resume_experiment(str(stopped), progress=None,
                                   experiments=[_experiment(**dict(start, **changed))])
    assert "\n" not in str(raised.value)
    assert physgrad.resume_experiment(str(stopped), progress=None,
                                      experiments=[_experiment(**start)]).finished


def test_find_lr_refuses_when_no_candidate_lowers_the_loss():
    model, closure = _problem()

    def uphill():  # the step direction reversed: every small step size raises the loss
        loss, j, g = closure()
        return loss, j, -g

    opt = pt.HIG(model.parameters(), lr=0.5)
    before = [p.detach().clone() for p in model.parameters()]

    def evaluate():
        with torch.enable_grad():
            return closure()[0]

    with pytest.raises(physgrad.NumericalError, match="no candidate step size lowers the loss"):
        opt.find_lr(uphill, evaluate, candidates=(0.001, 0.003, 0.01))
    assert opt.param_groups[0]["lr"] == 0.5
    assert all(torch.equal(p, b) for p, b in zip(model.parameters(), before))


@pytest.mark.parametrize("option, value", [("refresh", 2**31), ("products", 2**31),
                                           ("patience", 2**31), ("decay-every", 2**32)])
def test_a_count_beyond_an_int_is_refused_before_a_folder_is_claimed(tmp_path, option, value):
    with pytest.raises(physgrad.Error, match=f"{option}.*2147483647") as raised:
        physgrad.run_experiment("hig-toy", {option: value, "iters": 2}, str(tmp_path / "run"),
                                progress=None)
    assert "\n" not in str(raised.value)
    assert not (tmp_path / "run").exists()


def test_a_failed_own_run_names_the_python_call_that_resumes_it(tmp_path):
    class BreaksLater(Square):
        calls = 0

        def forward(self, y):
            BreaksLater.calls += 1
            if BreaksLater.calls > 400:
                raise KeyError("broken later")
            return super().forward(y)

    own = _experiment(simulator=BreaksLater(), rules={"adam": {"lr": 0.01, "batch": 8}})
    with pytest.raises(KeyError, match="broken later") as raised:
        physgrad.run_experiment("own", {"optimizers": "adam", "checkpoint-every": 1},
                                str(tmp_path / "run"), progress=None, experiments=[own])
    text = str(raised.value)
    assert "checkpoint kept" in text, text
    assert "physgrad.resume_experiment(" in text and "physgrad resume " not in text, text
    assert (tmp_path / "run" / "checkpoint.pgc").exists()
