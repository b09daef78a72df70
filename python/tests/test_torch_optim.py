# physgrad.torch's optimizers as torch.optim's are used, and its batched autodiff Jacobians.
import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt


def _problem(dtype=torch.float64, seed=0):
    torch.manual_seed(seed)
    model = torch.nn.Sequential(torch.nn.Linear(2, 4), torch.nn.Tanh(),
                                torch.nn.Linear(4, 3)).to(dtype)
    inputs = torch.linspace(-1, 1, 20, dtype=dtype).reshape(10, 2)
    targets = torch.sin(torch.arange(30, dtype=dtype)).reshape(10, 3)
    simulate = lambda x: torch.stack([x[:, 0], 10 * x[:, 1], x[:, 2] ** 2], 1)  # noqa: E731
    loss = lambda y, t: 0.5 * ((y - t) ** 2).sum(1).mean()  # noqa: E731
    return model, simulate, loss, inputs, targets


def test_frozen_parameters_are_skipped_and_a_subset_trains_with_its_own_jacobian():
    model, simulate, loss, inputs, targets = _problem()
    model[0].weight.requires_grad_(False)
    frozen = model[0].weight.detach().clone()
    opt = pt.HIG(model.parameters(), lr=0.5)
    closure = pt.jacobian_closure(model, simulate, loss, inputs, targets)
    assert closure()[1].shape == (10, 3, 4 + 12 + 3)  # no columns for the frozen 4×2 weight
    opt.step(closure)
    assert torch.equal(model[0].weight, frozen)
    last = list(model[2].parameters())
    before = [p.detach().clone() for p in model.parameters()]
    opt = pt.GN(last, lr=0.5)
    opt.step(pt.jacobian_closure(model, simulate, loss, inputs, targets, params=last))
    changed = [not torch.equal(p, b) for p, b in zip(model.parameters(), before)]
    assert changed == [False, False, True, True]


def test_param_groups_share_the_inversion_and_scale_their_part_of_the_step():
    model, simulate, loss, inputs, targets = _problem()
    closure = pt.jacobian_closure(model, simulate, loss, inputs, targets)
    _, j, g = closure()
    delta, _ = physgrad.jacobian_step(j.numpy(), g.reshape(-1).numpy(), lr=1.0)
    before = torch.cat([p.detach().reshape(-1) for p in model.parameters()])
    opt = pt.HIG([{"params": model[0].parameters(), "lr": 0.25},
                  {"params": model[2].parameters()}], lr=2.0)
    opt.step(closure)
    after = torch.cat([p.detach().reshape(-1) for p in model.parameters()])
    scale = torch.tensor([0.25] * 12 + [2.0] * 15, dtype=torch.float64)
    torch.testing.assert_close(after - before, scale * torch.from_numpy(delta), rtol=1e-12,
                               atol=1e-15)
    with pytest.raises(physgrad.Error, match="rcond 0.001 differs from the first group's"):
        opt.add_param_group({"params": [torch.nn.Parameter(torch.zeros(1))], "rcond": 1e-3})


def test_options_are_checked_when_the_optimizer_is_made():
    p = [torch.nn.Parameter(torch.zeros(2))]
    with pytest.raises(physgrad.Error, match="lr"):
        pt.HIG(p, lr=-1)
    with pytest.raises(physgrad.Error, match="rcond"):
        pt.GN(p, rcond=5)
    with pytest.raises(physgrad.Error, match="hig: unknown option 'lrr'"):
        pt.HIG(p, lrr=1.0)
    with pytest.raises(physgrad.Error, match="precision"):
        pt.HIG(p, precision="quad")


def test_the_state_dict_round_trip_gives_the_same_next_step():
    results = []
    for reload in (False, True):
        model, simulate, loss, inputs, targets = _problem()
        closure = pt.jacobian_closure(model, simulate, loss, inputs, targets)
        opt = pt.HIG(model.parameters(), lr=0.5, precision="auto")
        opt.step(closure)
        if reload:
            saved = opt.state_dict()
            assert saved["physgrad"]["previous"] is not None
            opt = pt.HIG(model.parameters(), lr=7.0, precision="auto")
            opt.load_state_dict(saved)
            assert opt.param_groups[0]["lr"] == 0.5
        opt.step(closure)
        results.append(torch.cat([p.detach().reshape(-1) for p in model.parameters()]))
    assert torch.equal(results[0], results[1])


def test_a_float32_model_keeps_float32_and_its_jacobian_is_not_widened():
    model, simulate, loss, inputs, targets = _problem(torch.float32)
    closure = pt.jacobian_closure(model, simulate, loss, inputs, targets)
    assert closure()[1].dtype == torch.float32
    opt = pt.HIG(model.parameters(), lr=0.5, rcond=1e-3)  # float32 rounding, not amplified
    opt.step(closure)
    assert opt.last_info["converted"]  # the library's one conversion to double
    assert all(p.dtype == torch.float32 for p in model.parameters())
    wide, *rest = _problem(torch.float64)
    pt.HIG(wide.parameters(), lr=0.5, rcond=1e-3).step(pt.jacobian_closure(wide, *rest))
    for p, q in zip(model.parameters(), wide.parameters()):
        torch.testing.assert_close(p, q.float(), rtol=1e-3, atol=1e-4)


@pytest.mark.skipif(not torch.cuda.is_available(), reason="no CUDA device here")
def test_parameters_on_a_gpu_are_updated_where_they_are():
    model, simulate, loss, inputs, targets = _problem(torch.float32)
    model, inputs, targets = model.cuda(), inputs.cuda(), targets.cuda()
    opt = pt.HIG(model.parameters(), lr=0.5)
    first = float(loss(simulate(model(inputs)), targets))
    for _ in range(3):
        opt.step(pt.jacobian_closure(model, simulate, loss, inputs, targets))
    assert all(p.is_cuda and p.dtype == torch.float32 for p in model.parameters())
    assert float(loss(simulate(model(inputs)), targets)) < first


@pytest.mark.parametrize("mode", ["fwd", "rev"])
def test_the_batched_jacobian_matches_finite_differences_in_either_mode(mode):
    model, simulate, loss, inputs, targets = _problem()
    j = pt.per_sample_jacobian(model, simulate, inputs, mode=mode)
    params = list(model.parameters())
    theta = torch.cat([p.detach().reshape(-1) for p in params])
    h = 1e-6
    for q in range(0, theta.numel(), 4):
        with torch.no_grad():
            shifted = []
            for sign in (1, -1):
                t = theta.clone()
                t[q] += sign * h
                torch.nn.utils.vector_to_parameters(t, params)
                shifted.append(simulate(model(inputs)))
            torch.nn.utils.vector_to_parameters(theta, params)
        np.testing.assert_allclose(j[:, :, q], (shifted[0] - shifted[1]) / (2 * h), atol=1e-7)
    torch.testing.assert_close(j, pt.per_sample_jacobian(model, simulate, inputs, chunk=3,
                                                         mode="rev" if mode == "fwd" else "fwd"))


def test_the_chunk_follows_the_memory_budget(monkeypatch):
    assert pt.choose_chunk(64, 1000) == 64  # 64 kB fit
    monkeypatch.setenv("PHYSGRAD_JACOBIAN_MEMORY", "10000")
    assert pt.choose_chunk(64, 1000) == 10 and pt.choose_chunk(64, 10**9) == 1
    assert pt.choose_mode(1744, 4) == "rev" and pt.choose_mode(4, 400) == "fwd"


@pytest.mark.parametrize("mode", ["auto", "fwd", "rev"])
def test_a_torch_simulators_jacobian_is_its_derivative(mode):
    def simulate(x):  # (B, 3) → (B, 5), nonlinear
        return torch.stack([x[:, 0] * x[:, 1], torch.sin(x[:, 2]), x[:, 0] ** 3,
                            x[:, 1] + x[:, 2], torch.exp(x[:, 0])], 1)

    sim = pt.TorchSimulator(simulate, mode=mode)
    x = np.array([0.3, -0.7, 1.1])
    h = 1e-6
    fd = np.stack([(sim.forward(x + h * e) - sim.forward(x - h * e)) / (2 * h)
                   for e in np.eye(3)], 1)
    np.testing.assert_allclose(sim.jacobian(x), fd, atol=1e-8)


def test_find_lr_picks_the_best_candidate_and_leaves_the_parameters():
    model, simulate, loss, inputs, targets = _problem()
    before = [p.detach().clone() for p in model.parameters()]
    opt = pt.HIG(model.parameters())
    closure = pt.jacobian_closure(model, simulate, loss, inputs, targets)
    losses = opt.find_lr(closure, lambda: loss(simulate(model(inputs)), targets))
    assert set(losses) == {0, 0.25, 0.5, 1.0, 2.0, 4.0, 8.0}  # 0: the loss before the step
    lower = {lr: l for lr, l in losses.items() if lr != 0 and l < losses[0]}
    assert lower and opt.param_groups[0]["lr"] == min(lower, key=lower.get)
    assert all(torch.equal(p, b) for p, b in zip(model.parameters(), before))


def test_the_keyword_defaults_are_the_catalogues():
    import inspect
    for cls, rule in ((pt.HIG, "hig"), (pt.GN, "gn")):
        defaults = physgrad.rule_defaults(rule)
        parameters = inspect.signature(cls).parameters
        for name in ("lr", "kappa", "rcond", "backend", "precision", "eigensolver"):
            assert parameters[name].default == defaults[name], (rule, name)
    assert physgrad.rule_defaults("gn")["kappa"] == 1.0
    assert physgrad.rule_defaults("hig")["kappa"] == 0.5
    assert inspect.signature(pt.SIP).parameters["lr"].default == \
        physgrad.rule_defaults("sip")["lr"]
    hig = physgrad.rule_defaults("hig")
    assert f"kappa: float = {hig['kappa']}" in physgrad.jacobian_step.__doc__
    assert f"rcond: float = {hig['rcond']}" in physgrad.jacobian_step.__doc__
    model, *_ = _problem()
    assert pt.HIG(model.parameters()).defaults["kappa"] == hig["kappa"]
    # Direct rules by kind; an unknown rule or kind is an Error naming it.
    assert physgrad.rule_defaults("gn", kind="direct") != physgrad.rule_defaults("gn")
    assert "kappa" not in physgrad.rule_defaults("gn", kind="direct")
    with pytest.raises(physgrad.Error, match="'both'"):
        physgrad.rule_defaults("gn", kind="both")
    with pytest.raises(physgrad.Error, match="'lbfgs'"):
        physgrad.rule_defaults("lbfgs")
