# physgrad.torch: the library's Jacobian step on torch tensors, read in place.
import numpy as np
import pytest
import torch

import physgrad
import physgrad.torch as pt


def test_the_library_reads_the_tensors_own_memory():
    torch.manual_seed(0)
    jacobian = torch.randn(8, 3, 50, dtype=torch.float64)
    dl_dy = torch.randn(8, 3, dtype=torch.float64)
    opt = pt.HIG([torch.nn.Parameter(torch.zeros(50, dtype=torch.float64))], rcond=1e-6)
    delta, info = opt.jacobian_step(jacobian, dl_dy)
    assert info["data_address"] == jacobian.data_ptr()
    assert not info["converted"] and info["backend"] == "gram"
    # The same step on a copy in another layout gives the same numbers from other memory.
    again, info2 = opt.jacobian_step(jacobian.clone(), dl_dy)
    assert info2["data_address"] != jacobian.data_ptr()
    np.testing.assert_array_equal(delta, again)


def test_float32_is_converted_once_and_gives_the_float64_step():
    torch.manual_seed(1)
    jacobian = torch.randn(4, 2, 30, dtype=torch.float32)
    dl_dy = torch.randn(4, 2)
    opt = pt.GN([torch.nn.Parameter(torch.zeros(30))])
    delta32, info = opt.jacobian_step(jacobian, dl_dy)
    delta64, _ = opt.jacobian_step(jacobian.double(), dl_dy.double())
    assert info["converted"]
    np.testing.assert_array_equal(delta32, delta64)


def test_gn_solves_a_linear_least_squares_problem_exactly():
    # J Δθ = −g for wide J: Gauss-Newton with lr 1 is the minimum-norm solution.
    torch.manual_seed(2)
    j = torch.randn(6, 1, 20, dtype=torch.float64)
    g = torch.randn(6, 1, dtype=torch.float64)
    delta, _ = pt.GN([torch.nn.Parameter(torch.zeros(20))], rcond=1e-12).jacobian_step(j, g)
    expected = -torch.linalg.pinv(j.reshape(6, 20)) @ g.reshape(6)
    np.testing.assert_allclose(delta, expected.numpy(), rtol=1e-9, atol=1e-12)


def test_a_non_contiguous_jacobian_is_refused():
    j = torch.randn(20, 2, 4, dtype=torch.float64).transpose(0, 2)
    with pytest.raises(physgrad.Error, match="not C-contiguous"):
        pt.HIG([torch.nn.Parameter(torch.zeros(20))]).jacobian_step(j, torch.zeros(4, 2))


def test_the_first_hig_step_agrees_with_the_library_on_the_oscillator_network():
    ref = physgrad.reference_step("oscillators", 128, "hig")
    jacobian = torch.from_numpy(ref["jacobian"])
    assert tuple(jacobian.shape) == (128, 4, 2956)
    theta = torch.nn.Parameter(torch.from_numpy(ref["parameters"].copy()))
    params = ref["params"]
    opt = pt.HIG([theta], lr=params["lr"], rcond=params["rcond"], backend=params["backend"])
    delta, info = opt.jacobian_step(jacobian, torch.from_numpy(ref["loss_gradient_y"]))
    assert info["data_address"] == jacobian.data_ptr()
    relative = lambda a, b: np.linalg.norm(a - b) / np.linalg.norm(b)
    # The same step from C++ on the same Jacobian.
    assert relative(delta, ref["delta_formed"]) <= 1e-12, relative(delta, ref["delta_formed"])
    # The step train() makes forms J Jᵀ from the network's layer factors instead: the rounding of
    # that Gram matrix differs, and τ = 1e-6 keeps σ down to 1e-6·σ_max, whose directions
    # amplify it (up to ε·(σ_max/σ_min)²); measured 1.1e-7.
    assert relative(delta, ref["delta"]) <= 1e-5, relative(delta, ref["delta"])


def test_the_chunked_jacobian_is_the_per_sample_jacobian():
    torch.manual_seed(3)
    model = torch.nn.Sequential(torch.nn.Linear(2, 5), torch.nn.Tanh(), torch.nn.Linear(5, 3))
    model.double()
    simulate = lambda x: torch.stack([x[:, 0] * x[:, 1], torch.sin(x[:, 2])], dim=1)
    inputs = torch.randn(7, 2, dtype=torch.float64)
    whole = pt.per_sample_jacobian(model, simulate, inputs)
    chunked = pt.per_sample_jacobian(model, simulate, inputs, chunk=3)
    assert tuple(whole.shape) == (7, 2, sum(p.numel() for p in model.parameters()))
    torch.testing.assert_close(whole, chunked, rtol=0, atol=0)
    # Row (i, k) against autograd on sample i alone.
    for i in (0, 6):
        y = simulate(model(inputs[i:i + 1]))[0]
        for k in range(2):
            grads = torch.autograd.grad(y[k], list(model.parameters()), retain_graph=True)
            row = torch.cat([g.reshape(-1) for g in grads])
            torch.testing.assert_close(whole[i, k], row, rtol=1e-12, atol=1e-12)


def test_hig_trains_a_network_through_a_differentiable_simulator():
    # A network maps x to controls c; the "physics" y = (c₁, λ·c₂) with λ = 0.01 is badly scaled.
    torch.manual_seed(4)
    lam = 0.01
    simulate = lambda c: torch.stack([c[:, 0], lam * c[:, 1]], dim=1)
    inputs = torch.linspace(-1, 1, 32, dtype=torch.float64).unsqueeze(1)
    targets = torch.cat([torch.sin(2 * inputs), lam * torch.cos(3 * inputs)], dim=1)
    loss_fn = lambda y, t: 0.5 * ((y - t) ** 2).sum(dim=1).mean()

    def trained(make_optimizer, steps):
        torch.manual_seed(5)
        model = torch.nn.Sequential(torch.nn.Linear(1, 16), torch.nn.Tanh(),
                                    torch.nn.Linear(16, 2)).double()
        opt = make_optimizer(model)
        closure = pt.jacobian_closure(model, simulate, loss_fn, inputs, targets, chunk=8)
        first = float(closure()[0])
        for _ in range(steps):
            opt.step(closure)
        return first, float(loss_fn(simulate(model(inputs)), targets))

    def adam_step(opt, closure):
        opt.zero_grad()
        loss = closure()
        loss.backward()
        opt.step()

    torch.manual_seed(5)
    model = torch.nn.Sequential(torch.nn.Linear(1, 16), torch.nn.Tanh(),
                                torch.nn.Linear(16, 2)).double()
    adam = torch.optim.Adam(model.parameters(), lr=1e-2)
    for _ in range(40):
        adam_step(adam, lambda: loss_fn(simulate(model(inputs)), targets))
    adam_loss = float(loss_fn(simulate(model(inputs)), targets))

    first, hig = trained(lambda m: pt.HIG(m.parameters(), lr=1.0, rcond=1e-6), 40)
    # Measured: 0.19 → 2.2e-3 with HIG, 1.3e-2 with Adam.
    assert hig < 0.02 * first and hig < 0.5 * adam_loss, (first, hig, adam_loss)
