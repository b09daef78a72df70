# physgrad.torch's structured rules (KFAC, KFACHIG, LanczosGN, LanczosHIG): the library's updates,
# exactness where the factorisation is exact, and torch.optim's habits.
import copy

import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt
from physgrad import _physgrad

SCALES = torch.tensor([1.0, 10.0, 0.5], dtype=torch.float64)


def _mlp(dtype=torch.float64, seed=0, batch=10):
    torch.manual_seed(seed)
    model = torch.nn.Sequential(torch.nn.Linear(2, 5), torch.nn.Tanh(),
                                torch.nn.Linear(5, 3)).to(dtype)
    inputs = torch.linspace(-1, 1, 2 * batch, dtype=dtype).reshape(batch, 2)
    targets = torch.sin(torch.arange(3 * batch, dtype=dtype)).reshape(batch, 3)
    simulate = lambda x: x * SCALES.to(x)  # noqa: E731
    return model, simulate, inputs, targets


def _loss(y, t):
    return 0.5 * ((y - t) ** 2).sum(1).mean()


def _flat(model):
    return torch.cat([p.detach().reshape(-1).to(torch.float64) for p in model.parameters()])


def _step(opt, model, closure):
    before = _flat(model)
    opt.step(closure)
    return _flat(model) - before


@pytest.mark.parametrize("rule,cls,options", [
    ("kfac", pt.KFAC, {}), ("kfac-hig", pt.KFACHIG, {}),
    ("kfac-hig", pt.KFACHIG, {"damping": 0.3, "rcond": 0.2}),
    ("lanczos-gn", pt.LanczosGN, {"products": 6}), ("lanczos-hig", pt.LanczosHIG, {"products": 6})])
def test_the_torch_update_equals_the_library_rule_on_the_same_mlp_and_batch(rule, cls, options):
    model, simulate, inputs, targets = _mlp()
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    w1, b1, w2, b2 = [p.detach() for p in model.parameters()]
    theta = torch.cat([w1.T.reshape(-1), b1, w2.T.reshape(-1), b2]).numpy()
    dl_dy = closure().dl_dy.reshape(-1).numpy()
    expected = _physgrad._structured_mlp_step(rule, dict(options, lr=0.7), [2, 5, 3], "tanh",
                                              theta, inputs.numpy(), SCALES.numpy(), dl_dy)
    got = _step(cls(model.parameters(), model, lr=0.7, **options), model, closure)
    # The library's θ order: W column by column, then b, per layer.
    got = torch.cat([got[:10].reshape(5, 2).T.reshape(-1), got[10:15],
                     got[15:30].reshape(3, 5).T.reshape(-1), got[30:]]).numpy()
    assert np.linalg.norm(expected) > 1e-3
    assert np.linalg.norm(got - expected) <= 1e-10 * np.linalg.norm(expected)


@pytest.mark.parametrize("rule,cls", [("lanczos-gn", pt.LanczosGN), ("lanczos-hig", pt.LanczosHIG)])
def test_lanczos_at_twenty_products_agrees_with_the_library_to_its_conditioning(rule, cls):
    # With 20 of the 30 rows the last Ritz values of this Jacobian lie near 1e-12·θ_max, where
    # rounding decides them: the two runs agree to about 3e-5, not to 1e-10 (6 products: 1e-12).
    model, simulate, inputs, targets = _mlp()
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    w1, b1, w2, b2 = [p.detach() for p in model.parameters()]
    theta = torch.cat([w1.T.reshape(-1), b1, w2.T.reshape(-1), b2]).numpy()
    expected = _physgrad._structured_mlp_step(rule, {}, [2, 5, 3], "tanh", theta, inputs.numpy(),
                                              SCALES.numpy(), closure().dl_dy.reshape(-1).numpy())
    got = _step(cls(model.parameters(), model), model, closure)
    got = torch.cat([got[:10].reshape(5, 2).T.reshape(-1), got[10:15],
                     got[15:30].reshape(3, 5).T.reshape(-1), got[30:]]).numpy()
    assert np.linalg.norm(got - expected) <= 1e-3 * np.linalg.norm(expected)


def test_the_defaults_are_the_library_rules_defaults():
    model, *_ = _mlp()
    kfac = pt.KFAC(model.parameters(), model).defaults
    assert kfac == dict(lr=1.0, kappa=1.0, rcond=1e-6, damping=1e-2, refresh=10,
                        factor_decay=0.9)
    assert pt.KFACHIG(model.parameters(), model).defaults["kappa"] == 0.5
    assert pt.LanczosGN(model.parameters(), model).defaults == dict(lr=1.0, kappa=1.0,
                                                                   rcond=1e-6, products=20)
    assert pt.LanczosHIG(model.parameters(), model).defaults["kappa"] == 0.5
    table = {r["id"]: r["defaults"] for r in physgrad.learning_rules()}
    assert "damping" in table["kfac-hig"] and "products" in table["lanczos-hig"]


def _conv_case(layer, shape, batch, seed=1):
    torch.manual_seed(seed)
    model = torch.nn.Sequential(layer).to(torch.float64)
    inputs = torch.randn(batch, *shape, dtype=torch.float64)
    with torch.no_grad():
        out = model(inputs).reshape(batch, -1)
    targets = torch.randn_like(out)
    simulate = lambda z: z.reshape(z.shape[0], -1)  # noqa: E731  identity physics
    return model, simulate, inputs, targets


@pytest.mark.parametrize("layer,shape,batch", [
    (torch.nn.Conv1d(3, 4, 5), (3, 5), 20),  # one output position: the dense layer
    (torch.nn.Conv1d(2, 3, 3, padding="same", padding_mode="circular"), (2, 6), 4),
    (torch.nn.Conv2d(2, 3, 3, stride=2, padding=1), (2, 5, 5), 6)])
def test_kfac_hig_equals_exact_hig_on_a_conv_layer_with_identity_physics(layer, shape, batch):
    # One layer, y = z: every cotangent is a unit vector at one position, JᵀJ = B·A ⊗ I = A ⊗ S
    # exactly, and (A ⊗ S)^{−¾} without damping is HIG's (JᵀJ)^{−¾}.
    model, simulate, inputs, targets = _conv_case(layer, shape, batch)
    exact = copy.deepcopy(model)
    got = _step(pt.KFACHIG(model.parameters(), model, damping=0.0), model,
                pt.structured_closure(model, simulate, _loss, inputs, targets))
    want = _step(pt.HIG(exact.parameters()), exact,
                 pt.jacobian_closure(exact, simulate, _loss, inputs, targets))
    assert float(want.norm()) > 1e-3
    assert float((got - want).norm()) <= 1e-10 * float(want.norm())


@pytest.mark.parametrize("cls,exact", [(pt.LanczosHIG, pt.HIG), (pt.LanczosGN, pt.GN)])
def test_lanczos_with_every_row_is_the_exact_step_on_a_conv_net(cls, exact):
    torch.manual_seed(2)
    model = torch.nn.Sequential(torch.nn.Conv1d(1, 2, 3, padding=1), torch.nn.Tanh(),
                                torch.nn.Conv1d(2, 1, 3, padding=1)).to(torch.float64)
    inputs = torch.randn(3, 1, 6, dtype=torch.float64)
    targets = torch.randn(3, 6, dtype=torch.float64)
    simulate = lambda z: torch.fft.irfft(torch.fft.rfft(z[:, 0]) * 0.5, n=6)  # noqa: E731
    other = copy.deepcopy(model)
    got = _step(cls(model.parameters(), model, products=18), model,
                pt.structured_closure(model, simulate, _loss, inputs, targets))
    want = _step(exact(other.parameters()), other,
                 pt.jacobian_closure(other, simulate, _loss, inputs, targets))
    assert float((got - want).norm()) <= 1e-8 * float(want.norm())


def test_param_groups_scale_their_part_and_frozen_parameters_stay():
    model, simulate, inputs, targets = _mlp()
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    whole = _step(pt.KFACHIG(model.parameters(), model), model, closure)
    model, simulate, inputs, targets = _mlp()
    closure = pt.structured_closure(model, simulate, _loss, inputs, targets)
    opt = pt.KFACHIG([{"params": model[0].parameters(), "lr": 0.25},
                      {"params": model[2].parameters()}], model, lr=2.0)
    scale = torch.tensor([0.25] * 15 + [2.0] * 18, dtype=torch.float64)
    torch.testing.assert_close(_step(opt, model, closure), scale * whole, rtol=1e-12, atol=1e-15)
    with pytest.raises(physgrad.Error, match="refresh 3 differs from the first group's 10"):
        opt.add_param_group({"params": [torch.nn.Parameter(torch.zeros(1))], "refresh": 3})
    for cls in (pt.KFAC, pt.LanczosHIG):
        model, simulate, inputs, targets = _mlp()
        model[0].bias.requires_grad_(False)
        frozen = model[0].bias.detach().clone()
        delta = _step(cls(model.parameters(), model), model,
                      pt.structured_closure(model, simulate, _loss, inputs, targets))
        assert torch.equal(model[0].bias, frozen)
        assert float(delta.abs().min()) == 0 and float(delta[:10].norm()) > 0


@pytest.mark.parametrize("cls", [pt.KFAC, pt.LanczosGN])
def test_a_state_dict_round_trip_continues_identically(cls):
    model, simulate, inputs, targets = _mlp()
    opt = cls(model.parameters(), model, lr=0.5, **({"refresh": 2} if cls is pt.KFAC else {}))
    batches = [(inputs * (1 + 0.1 * k), targets) for k in range(6)]
    for x, t in batches[:3]:
        opt.step(pt.structured_closure(model, simulate, _loss, x, t))
    other = copy.deepcopy(model)
    resumed = cls(other.parameters(), other, lr=3.0)
    resumed.load_state_dict(copy.deepcopy(opt.state_dict()))
    assert resumed.param_groups[0]["lr"] == 0.5
    for x, t in batches[3:]:
        opt.step(pt.structured_closure(model, simulate, _loss, x, t))
        resumed.step(pt.structured_closure(other, simulate, _loss, x, t))
    assert torch.equal(_flat(model), _flat(other))


def test_bad_options_and_other_layers_are_refused_before_anything_changes():
    model, simulate, inputs, targets = _mlp()
    with pytest.raises(physgrad.Error, match="damping"):
        pt.KFAC(model.parameters(), model, damping=-1)
    with pytest.raises(physgrad.Error, match="products"):
        pt.LanczosHIG(model.parameters(), model, products=0)
    with pytest.raises(physgrad.Error, match="unknown option"):
        pt.KFACHIG(model.parameters(), model, products=3)
    net = torch.nn.Sequential(torch.nn.Linear(2, 3), torch.nn.BatchNorm1d(3))
    with pytest.raises(physgrad.Error, match=r"^kfac: layer '1' \(BatchNorm1d\) has trainable"):
        pt.KFAC(net.parameters(), net)
    opt = pt.KFACHIG(model.parameters(), model)
    with pytest.raises(physgrad.Error, match="rcond"):
        opt.load_state_dict(dict(opt.state_dict(), param_groups=[
            dict(opt.state_dict()["param_groups"][0], rcond=2.0)]))
    before = _flat(model)
    bad = targets.clone()
    bad[3, 1] = float("nan")
    for cls in (pt.KFACHIG, pt.LanczosGN):
        with pytest.raises(physgrad.NumericalError, match="the loss is nan"):
            cls(model.parameters(), model).step(
                pt.structured_closure(model, simulate, _loss, inputs, bad))
    assert torch.equal(_flat(model), before)


@pytest.mark.parametrize("cls", [pt.KFACHIG, pt.LanczosHIG])
def test_float32_steps_in_float32_and_agree_with_float64(cls):
    # The same cut in both (float32 raises Lanczos's to √ε = 3.5e-4 on its own).
    steps = []
    for dtype in (torch.float32, torch.float64):
        model, simulate, inputs, targets = _mlp(dtype)
        steps.append(_step(cls(model.parameters(), model, lr=0.5, rcond=1e-3), model,
                           pt.structured_closure(model, simulate, _loss, inputs, targets)))
        assert all(p.dtype == dtype for p in model.parameters())
    # float32 products err by ~1e-7·θ_max, i.e. ~10 % on a Ritz value at the cut 1e-6·θ_max;
    # the Kronecker factors' eigenvalues are better separated.
    tolerance = 5e-2 if cls is pt.LanczosHIG else 1e-3
    assert float((steps[0] - steps[1]).norm()) <= tolerance * float(steps[1].norm())


def test_the_lanczos_products_are_the_jacobian_by_central_differences():
    model, simulate, inputs, targets = _mlp()
    opt = pt.LanczosGN(model.parameters(), model)
    batch = pt.structured_closure(model, simulate, _loss, inputs, targets)()
    pairs = opt._trainable()
    forward, backward = opt._products(batch, pairs)
    torch.manual_seed(3)
    w = torch.randn(sum(p.numel() for _, p in pairs), dtype=torch.float64)
    c = torch.randn(batch.dl_dy.numel(), dtype=torch.float64)
    theta = torch.nn.utils.parameters_to_vector(model.parameters()).detach()
    ys = []
    for sign in (1, -1):
        torch.nn.utils.vector_to_parameters(theta + sign * 1e-6 * w, model.parameters())
        with torch.no_grad():
            ys.append(batch.forward().reshape(-1))
    torch.nn.utils.vector_to_parameters(theta, model.parameters())
    difference = (ys[0] - ys[1]) / 2e-6
    with torch.enable_grad():
        jw, jtc = forward(w), backward(c)
    torch.testing.assert_close(jw, difference, rtol=1e-7, atol=1e-8)
    torch.testing.assert_close(float(jtc @ w), float(c @ jw), rtol=1e-12, atol=0)
