# What a Python user expects of results and of mistakes: results behave as the dicts they
# replace (len, iteration, json), and each misuse of the torch optimizers is one line naming it.
import json

import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt


def test_a_run_outcome_is_a_dict(tmp_path):
    outcome = physgrad.run_experiment("scaled-toy", {"iters": 2}, str(tmp_path / "a"),
                                      progress=None)
    assert list(outcome) == ["folder", "finished", "report", "stopped", "summary"]
    assert len(outcome) == 5 and outcome["finished"] and outcome.finished
    assert json.loads(json.dumps(outcome))["folder"] == outcome.folder
    assert dict(outcome)["summary"] == outcome.summary


def test_a_local_inverse_result_iterates_over_its_keys(scaled_toy):
    result = physgrad.local_inverse(scaled_toy(2.0), np.array([1.0, 1.0]), np.zeros(2))
    assert list(result) == ["x", "residual", "iterations", "evaluations", "counts", "converged"]
    assert len(result) == 6
    np.testing.assert_allclose(result["x"], [1.0, 0.5], atol=1e-8)
    with pytest.raises(AttributeError, match="no attribute 'y'"):
        result.y
    name, description = physgrad.experiments()[0]
    assert physgrad.experiments()[0]["name"] == name and physgrad.experiments()[0][1] == description


def _problem(model=None):
    torch.manual_seed(0)
    model = model or torch.nn.Sequential(torch.nn.Linear(2, 4), torch.nn.Tanh(),
                                         torch.nn.Linear(4, 2)).double()
    inputs = torch.linspace(-1, 1, 16, dtype=torch.float64).reshape(8, 2)
    simulate = lambda x: x ** 3  # noqa: E731
    loss = lambda y, t: 0.5 * ((y - t) ** 2).sum(1).mean()  # noqa: E731
    return model, simulate, loss, inputs, inputs.clone()


def _one_line(raised):
    assert "\n" not in str(raised.value), str(raised.value)


def test_misuses_of_hig_are_one_line_errors():
    model, simulate, loss, inputs, targets = _problem()
    opt = pt.HIG(model.parameters())
    with pytest.raises(physgrad.Error, match="step needs a closure") as raised:
        opt.step()
    _one_line(raised)
    with pytest.raises(physgrad.Error, match="returned a Tensor, expected \\(loss, J, dL_dy\\)"):
        opt.step(lambda: loss(simulate(model(inputs)), targets))  # an LBFGS closure
    sip = pt.sip_closure(model, simulate, inputs, targets)
    with pytest.raises(physgrad.Error, match="returned a tuple of 4"):
        opt.step(sip)
    with pytest.raises(physgrad.Error, match="inputs is a ndarray"):
        pt.jacobian_closure(model, simulate, loss, inputs.numpy(), targets)
    with pytest.raises(physgrad.Error, match="inputs is a ndarray"):
        pt.per_sample_jacobian(model, simulate, inputs.numpy())


def test_missing_parameters_are_named():
    model, *_ = _problem()
    params = model.parameters()
    pt.HIG(params)
    with pytest.raises(physgrad.Error, match="no parameters given.*exhausted generator"):
        pt.GN(params)  # the generator was read by the first optimizer
    model, simulate, loss, inputs, targets = _problem()
    for p in model.parameters():
        p.requires_grad_(False)
    opt = pt.HIG(model.parameters())
    with pytest.raises(physgrad.Error, match="no parameter trains"):
        opt.step(lambda: (torch.zeros(()), torch.zeros(8, 2, 0, dtype=torch.float64),
                          torch.zeros(8, 2, dtype=torch.float64)))


def test_batch_norm_in_training_mode_has_no_per_sample_jacobian():
    net = torch.nn.Sequential(torch.nn.Linear(2, 4), torch.nn.BatchNorm1d(4),
                              torch.nn.Linear(4, 2)).double()
    model, simulate, loss, inputs, targets = _problem(net)
    with pytest.raises(physgrad.Error, match="1 is a BatchNorm in training mode.*model.eval"):
        pt.jacobian_closure(model, simulate, loss, inputs, targets)()
    model.eval()
    assert pt.jacobian_closure(model, simulate, loss, inputs, targets)()[1].shape == (8, 2, 30)


def test_a_hig_closure_given_to_sip_is_named():
    model, simulate, loss, inputs, targets = _problem()
    opt = pt.SIP(model.parameters(), pt.TorchSimulator(simulate))
    with pytest.raises(physgrad.Error, match="sip: the closure returned a tuple of 3"):
        opt.step(pt.jacobian_closure(model, simulate, loss, inputs, targets))
    with pytest.raises(physgrad.Error, match="sip: step needs a closure"):
        opt.step()
    with pytest.raises(physgrad.Error, match="sip_closure: inputs is a ndarray"):
        pt.sip_closure(model, simulate, inputs.numpy(), targets)


def test_load_state_dict_refuses_mixed_groups_and_a_non_finite_spectrum():
    model, simulate, loss, inputs, targets = _problem()
    opt = pt.HIG([{"params": model[0].parameters()}, {"params": model[2].parameters()}])
    opt.step(pt.jacobian_closure(model, simulate, loss, inputs, targets))
    state = opt.state_dict()
    mixed = dict(state, param_groups=[dict(g) for g in state["param_groups"]])
    mixed["param_groups"][1]["rcond"] = 1e-3
    with pytest.raises(physgrad.Error, match="load_state_dict: rcond 0.001 differs"):
        pt.HIG([{"params": model[0].parameters()}, {"params": model[2].parameters()}]) \
            .load_state_dict(mixed)
    mixed["param_groups"][1]["rcond"] = state["param_groups"][0]["rcond"]
    mixed["param_groups"][1]["precision"] = "float"
    with pytest.raises(physgrad.Error, match="load_state_dict: precision 'float' differs"):
        pt.HIG([{"params": model[0].parameters()}, {"params": model[2].parameters()}]) \
            .load_state_dict(mixed)
    previous = json.loads(json.dumps(state["physgrad"]["previous"]))
    assert previous, "the step keeps a spectrum"

    def poison(value):
        if isinstance(value, dict):
            key = next(iter(value))
            value[key] = poison(value[key])
            return value
        if isinstance(value, list):
            return [poison(value[0])] + value[1:] if value else [float("nan")]
        return float("nan")

    broken = dict(state, physgrad={"previous": poison(previous)})
    with pytest.raises(physgrad.Error, match="saved spectrum.*not finite"):
        pt.HIG([{"params": model[0].parameters()}, {"params": model[2].parameters()}]) \
            .load_state_dict(broken)


def test_the_optimizers_show_their_keywords():
    import ast
    import inspect
    import pathlib
    for rule in (pt.HIG, pt.GN):
        names = list(inspect.signature(rule).parameters)
        assert names[:7] == ["params", "lr", "kappa", "rcond", "backend", "precision",
                             "eigensolver"], names
    stub = pathlib.Path(pt.__file__).with_name("__init__.pyi")
    tree = ast.parse(stub.read_text())
    classes = {node.name: node for node in tree.body if isinstance(node, ast.ClassDef)}
    for name in ("HIG", "GN", "SIP"):
        [init] = [f for f in classes[name].body if isinstance(f, ast.FunctionDef)
                  and f.name == "__init__"]
        assert "lr" in [a.arg for a in init.args.args], name
    assert "kappa" in [a.arg for a in [f for f in classes["HIG"].body
                                       if getattr(f, "name", "") == "__init__"][0].args.args]
