# physgrad.torch's KFAC/KFACHIG with sampled output directions (samples=K): exact with K = m (as
# the unsampled update and the library's), bad values named before any change, draws resumed
# from state_dict.
import copy

import numpy as np
import pytest
import torch

import physgrad.torch as pt
from physgrad import _physgrad

SCALES = torch.tensor([1.0, 10.0, 0.5], dtype=torch.float64)


def _mlp(seed=0, batch=10):
    torch.manual_seed(seed)
    model = torch.nn.Sequential(torch.nn.Linear(2, 5), torch.nn.Tanh(),
                                torch.nn.Linear(5, 3)).to(torch.float64)
    inputs = torch.linspace(-1, 1, 2 * batch, dtype=torch.float64).reshape(batch, 2)
    targets = torch.sin(torch.arange(3 * batch, dtype=torch.float64)).reshape(batch, 3)
    simulate = lambda x: x * SCALES.to(x)  # noqa: E731
    return model, simulate, inputs, targets


def _conv(seed=3, batch=4):
    # Two circular Conv1d layers through a smoothing linear physics: m = 6 outputs per sample.
    torch.manual_seed(seed)
    model = torch.nn.Sequential(
        torch.nn.Conv1d(1, 3, 3, padding=1, padding_mode="circular"), torch.nn.Tanh(),
        torch.nn.Conv1d(3, 1, 3, padding=1, padding_mode="circular")).to(torch.float64)
    inputs = torch.randn(batch, 1, 6, dtype=torch.float64)
    mix = torch.eye(6, dtype=torch.float64) + 0.3 * torch.roll(torch.eye(6, dtype=torch.float64),
                                                               1, 0)
    simulate = lambda z: z.reshape(z.shape[0], -1) @ mix.T  # noqa: E731
    targets = torch.randn(batch, 6, dtype=torch.float64)
    return model, simulate, inputs, targets


def _loss(y, t):
    return 0.5 * ((y - t) ** 2).sum(1).mean()


def _flat(model):
    return torch.cat([p.detach().reshape(-1) for p in model.parameters()])


def _step(opt, model, closure):
    before = _flat(model)
    opt.step(closure)
    return _flat(model) - before


@pytest.mark.parametrize("cls", [pt.KFAC, pt.KFACHIG])
@pytest.mark.parametrize("case,m", [(_mlp, 3), (_conv, 6)])
def test_every_output_as_a_direction_is_the_unsampled_update(cls, case, m):
    model, simulate, inputs, targets = case()
    other = copy.deepcopy(model)
    want = _step(cls(other.parameters(), other, lr=0.7),
                 other, pt.structured_closure(other, simulate, _loss, inputs, targets))
    got = _step(cls(model.parameters(), model, lr=0.7, samples=m),
                model, pt.structured_closure(model, simulate, _loss, inputs, targets))
    assert float(want.norm()) > 1e-3
    assert float((got - want).norm()) <= 1e-10 * float(want.norm())


@pytest.mark.parametrize("rule,cls", [("kfac", pt.KFAC), ("kfac-hig", pt.KFACHIG)])
def test_every_output_as_a_direction_equals_the_library_rule(rule, cls):
    model, simulate, inputs, targets = _mlp()
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    w1, b1, w2, b2 = [p.detach() for p in model.parameters()]
    theta = torch.cat([w1.T.reshape(-1), b1, w2.T.reshape(-1), b2]).numpy()
    dl_dy = closure().dl_dy.reshape(-1).numpy()
    expected = _physgrad._structured_mlp_step(rule, {"lr": 0.7, "samples": 3}, [2, 5, 3], "tanh",
                                              theta, inputs.numpy(), SCALES.numpy(), dl_dy)
    got = _step(cls(model.parameters(), model, lr=0.7, samples=3), model, closure)
    got = torch.cat([got[:10].reshape(5, 2).T.reshape(-1), got[10:15],
                     got[15:30].reshape(3, 5).T.reshape(-1), got[30:]]).numpy()
    assert np.linalg.norm(expected) > 1e-3
    assert np.linalg.norm(got - expected) <= 1e-10 * np.linalg.norm(expected)


def test_fewer_directions_give_another_update_that_still_descends():
    model, simulate, inputs, targets = _mlp()
    other = copy.deepcopy(model)
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    gradient = torch.autograd.grad(_loss(simulate(model(inputs)), targets),
                                   list(model.parameters()))
    gradient = torch.cat([g.reshape(-1) for g in gradient])
    want = _step(pt.KFACHIG(other.parameters(), other, lr=0.1),
                 other, pt.structured_closure(other, simulate, _loss, inputs, targets))
    got = _step(pt.KFACHIG(model.parameters(), model, lr=0.1, samples=1), model, closure)
    assert float((got - want).norm()) > 1e-3 * float(want.norm())
    assert float(got @ gradient) < 0


@pytest.mark.parametrize("bad", [-1, 2.5])
def test_a_bad_count_is_named_before_anything_is_made(bad):
    model, *_ = _mlp()
    with pytest.raises(_physgrad.Error, match=f"samples.*{bad}"):
        pt.KFACHIG(model.parameters(), model, samples=bad)


def test_more_directions_than_outputs_is_named_and_changes_nothing():
    model, simulate, inputs, targets = _mlp()
    opt = pt.KFAC(model.parameters(), model, samples=4)
    before = _flat(model).clone()
    state = copy.deepcopy(opt.state_dict())
    with pytest.raises(_physgrad.Error, match="samples 4 exceeds the 3 physics outputs"):
        opt.step(pt.structured_closure(model, simulate, _loss, inputs, targets))
    assert torch.equal(_flat(model), before)
    assert torch.equal(opt.state_dict()["physgrad"]["generator"], state["physgrad"]["generator"])
    assert opt.state_dict()["physgrad"]["steps"] == 0


def test_state_dict_resumes_the_same_draws():
    model, simulate, inputs, targets = _mlp()
    first = pt.KFACHIG(model.parameters(), model, lr=0.1, samples=2, refresh=1)
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    for _ in range(3):
        first.step(closure)
    twin = copy.deepcopy(model)
    second = pt.KFACHIG(twin.parameters(), twin, lr=0.1, samples=2, refresh=1)
    second.load_state_dict(copy.deepcopy(first.state_dict()))
    fresh_model = copy.deepcopy(model)
    fresh = pt.KFACHIG(fresh_model.parameters(), fresh_model, lr=0.1, samples=2, refresh=1)
    saved = first.state_dict()
    saved["physgrad"] = dict(saved["physgrad"], generator=None)
    fresh.load_state_dict(saved)  # the factors, but the generator from its seed: other draws
    a = _step(first, model, closure)
    b = _step(second, twin, pt.structured_closure(twin, simulate, _loss, inputs, targets))
    c = _step(fresh, fresh_model,
              pt.structured_closure(fresh_model, simulate, _loss, inputs, targets))
    assert torch.equal(a, b)
    assert not torch.equal(a, c)
