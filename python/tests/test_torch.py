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


def test_every_eigensolver_gives_the_svd_step():
    # Δθ = −V Σ^{−½} Uᵀ g for a well-conditioned J; auto with no history takes tridiagonal.
    torch.manual_seed(3)
    j = torch.randn(8, 4, 50, dtype=torch.float64)
    g = torch.randn(8, 4, dtype=torch.float64)
    u, s, vh = torch.linalg.svd(j.reshape(32, 50), full_matrices=False)
    expected = -(vh.T @ ((u.T @ g.reshape(32)) * s.pow(-0.5))).numpy()
    for eigensolver in ("tridiagonal", "full", "subset", "auto"):
        opt = pt.HIG([torch.nn.Parameter(torch.zeros(50))], eigensolver=eigensolver)
        delta, info = opt.jacobian_step(j, g)
        assert info["eigensolver"] == ("tridiagonal" if eigensolver == "auto" else eigensolver)
        np.testing.assert_allclose(delta, expected, rtol=1e-10, atol=1e-12)


def test_the_blas_kernels_are_named():
    core = physgrad.blas_core()
    assert core  # the build links OpenBLAS
    note = physgrad.blas_core_note()
    assert note == "" or (core in note and "OPENBLAS_CORETYPE=" in note)


def test_a_non_contiguous_jacobian_is_refused_by_the_array_call_and_copied_by_the_optimizer():
    j = torch.randn(20, 2, 4, dtype=torch.float64).transpose(0, 2)
    g = torch.randn(4, 2, dtype=torch.float64)
    with pytest.raises(physgrad.Error, match="not C-contiguous"):
        physgrad.jacobian_step(j.numpy(), g.numpy())
    opt = pt.HIG([torch.nn.Parameter(torch.zeros(20))])
    np.testing.assert_array_equal(opt.jacobian_step(j, g)[0],
                                  opt.jacobian_step(j.contiguous(), g)[0])


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


# SIP: a network u ↦ x trained through y = P(x) = (x₁, α·x₂) toward y* = P(x_true(u)).
def _scaled(alpha):
    return lambda x: x * torch.tensor([1.0, alpha], dtype=x.dtype)


def _sip_problem(alpha):
    u = torch.linspace(-1, 1, 32, dtype=torch.float64).unsqueeze(1)
    x_true = torch.cat([torch.sin(2 * u), torch.cos(3 * u)], dim=1)
    return u, x_true, _scaled(alpha)(x_true)


def _sip_model():
    torch.manual_seed(6)
    return torch.nn.Sequential(torch.nn.Linear(1, 16), torch.nn.Tanh(),
                               torch.nn.Linear(16, 2)).double()


def _x_error(model, u, x_true):
    with torch.no_grad():
        return float(((model(u) - x_true) ** 2).sum(dim=1).mean().sqrt())


def _train_sip(alpha, steps, simulator, **options):
    u, x_true, y_star = _sip_problem(alpha)
    model = _sip_model()
    opt = pt.SIP(model.parameters(), simulator, **options)
    closure = pt.sip_closure(model, _scaled(alpha), u, y_star)
    errors = [_x_error(model, u, x_true)]
    for _ in range(steps):
        opt.step(closure)
        errors.append(_x_error(model, u, x_true))
    return errors, opt


def _train_adam(alpha, steps, lr):
    u, x_true, y_star = _sip_problem(alpha)
    model = _sip_model()
    opt = torch.optim.Adam(model.parameters(), lr=lr)
    errors = [_x_error(model, u, x_true)]
    for _ in range(steps):
        opt.zero_grad()
        (0.5 * ((_scaled(alpha)(model(u)) - y_star) ** 2).sum(dim=1).mean()).backward()
        opt.step()
        errors.append(_x_error(model, u, x_true))
    return errors


def test_sip_trains_through_the_analytic_inverse_and_adam_does_not(scaled_toy):
    alpha = 0.01
    sip, opt = _train_sip(alpha, 200, scaled_toy(alpha), lr=3e-2)
    adam = _train_adam(alpha, 200, lr=3e-2)
    assert sip[0] == adam[0]
    # Measured: RMS x error 1.08 → SIP 0.051, Adam 0.57.
    assert sip[-1] < 0.1 * sip[0] and sip[-1] < 0.2 * adam[-1], (sip[0], sip[-1], adam[-1])
    info = opt.last_info
    assert info["converged"].all() and info["counts"]["inverses"] == 32
    assert info["residual"].max() < 1e-12 and info["proxy_loss"] >= 0


def test_sip_is_scale_invariant_and_adam_is_not(scaled_toy):
    # With y_step < 1 the proxy target x + η(x_true − x) still does not depend on α.
    sip = {a: _train_sip(a, 100, scaled_toy(a), lr=3e-2, y_step=0.5)[0] for a in (1.0, 0.01)}
    adam = {a: _train_adam(a, 100, lr=3e-2) for a in (1.0, 0.01)}
    np.testing.assert_allclose(sip[0.01], sip[1.0], rtol=1e-9)
    # Measured: Adam's x error after 100 steps 0.13 at α = 1, 0.64 at α = 0.01.
    assert adam[0.01][-1] > 2 * adam[1.0][-1], (adam[0.01][-1], adam[1.0][-1])


def test_the_proxy_target_reaches_the_y_step_by_a_numerical_inverse():
    # A nonlinear simulator without an inverse: lbfgs through the torch simulator's VJP.
    simulate = lambda x: torch.stack([x[:, 0] + 0.3 * x[:, 1] ** 2,
                                      0.01 * (x[:, 1] + 0.5 * torch.sin(x[:, 0]))], dim=1)
    sim = pt.TorchSimulator(simulate)
    torch.manual_seed(7)
    x = torch.randn(5, 2, dtype=torch.float64) * 0.5
    y = simulate(x)
    y_star = simulate(x + 0.2 * torch.randn(5, 2, dtype=torch.float64))
    opt = pt.SIP([torch.nn.Parameter(torch.zeros(1))], sim, y_step=0.5, inverse="lbfgs")
    x_tilde, info = opt.proxy_targets(x, y, y_star)
    assert info["converged"].all() and info["counts"]["vjp"] > 0
    torch.testing.assert_close(simulate(x_tilde), y + 0.5 * (y_star - y), rtol=0, atol=1e-9)
    assert float((x_tilde - x).abs().max()) > 1e-3  # it moved

    # The same through a torch inverse of the linear toy is that inverse's value.
    inverse = lambda y, x0: y / torch.tensor([1.0, 0.01], dtype=y.dtype)
    toy = pt.TorchSimulator(_scaled(0.01), inverse=inverse)
    opt = pt.SIP([torch.nn.Parameter(torch.zeros(1))], toy, inverse="analytic")
    y = _scaled(0.01)(x)
    x_tilde, info = opt.proxy_targets(x, y, y_star)
    torch.testing.assert_close(x_tilde, inverse(y_star, x), rtol=0, atol=1e-15)
    assert info["counts"]["inverses"] == 5 and info["counts"]["vjp"] == 0
    # A float32 batch gets float32 targets, the same numbers rounded.
    x_tilde32, _ = opt.proxy_targets(x.float(), y.float(), y_star.float())
    assert x_tilde32.dtype == torch.float32
    torch.testing.assert_close(x_tilde32, inverse(y_star.float(), x.float()))


def test_sip_trains_with_a_numerical_inverse_as_with_the_analytic_one(scaled_toy):
    # The toy is linear, so ig's first step and lbfgs's solve are the exact preimage.
    alpha = 0.01
    analytic, _ = _train_sip(alpha, 30, scaled_toy(alpha), lr=3e-2)
    for method in ("ig", "lbfgs"):
        errors, opt = _train_sip(alpha, 30, pt.TorchSimulator(_scaled(alpha)), lr=3e-2,
                                 inverse=method)
        np.testing.assert_allclose(errors, analytic, rtol=1e-6, err_msg=method)
        assert opt.last_info["iterations"] >= 32 and opt.last_info["counts"]["inverses"] == 0


def _bad_inverse_step(inverse):
    toy = pt.TorchSimulator(_scaled(0.01), inverse=inverse)
    model = _sip_model()
    before = [p.detach().clone() for p in model.parameters()]
    u, _, y_star = _sip_problem(0.01)
    opt = pt.SIP(model.parameters(), toy, lr=1e-2)
    try:
        opt.step(pt.sip_closure(model, _scaled(0.01), u, y_star))
    finally:
        for p, b in zip(model.parameters(), before):
            assert torch.equal(p, b), "a failed SIP step changed the parameters"


def test_a_bad_inverse_is_an_exception_naming_sip_and_the_sample():
    def wrong_shape(y, x0):
        return torch.zeros(1, 3, dtype=y.dtype)

    def nan_at_sample_4(y, x0):  # called once for the batch of 32
        x = x0.clone()
        x[4] = float("nan")
        return x

    def raising(y, x0):
        raise RuntimeError("no preimage here")

    with pytest.raises(physgrad.Error, match=r"^sip: the batch of 32: simulator 'torch simulator': "
                                             r"inverse_batch returned"):
        _bad_inverse_step(wrong_shape)
    with pytest.raises(physgrad.NumericalError,
                       match=r"^sip: sample 4 of 32: the local inverse \(auto\) gave no finite"):
        _bad_inverse_step(nan_at_sample_4)
    with pytest.raises(RuntimeError, match=r"no preimage here \(in sip, the batch of 32, local "
                                           r"inverse auto, inverse_batch\)"):
        _bad_inverse_step(raising)


def test_sip_refuses_bad_options_and_shapes(scaled_toy):
    param = [torch.nn.Parameter(torch.zeros(1))]
    with pytest.raises(physgrad.Error, match="sip: y_step must be"):
        pt.SIP(param, scaled_toy(1.0), y_step=-1.0)
    with pytest.raises(physgrad.Error, match="sip: unknown option 'rcond'"):
        pt.SIP(param, scaled_toy(1.0), rcond=1e-3)
    with pytest.raises(physgrad.Error, match="sip: inverse must be one of: auto, .*'newton'"):
        pt.SIP(param, scaled_toy(1.0), inverse="newton")
    opt = pt.SIP(param, scaled_toy(1.0))
    with pytest.raises(physgrad.Error, match=r"sip: x has shape \(4\), expected \(B, k\)"):
        opt.proxy_targets(torch.zeros(4), torch.zeros(4, 2), torch.zeros(4, 2))
    with pytest.raises(physgrad.Error, match=r"sip: x has shape \(4, 2\), y \(3, 2\) and the "
                                             r"target y\* \(4, 2\), expected"):
        opt.proxy_targets(torch.zeros(4, 2), torch.zeros(3, 2), torch.zeros(4, 2))
    with pytest.raises(physgrad.NumericalError, match="sample 1 of 2: the simulator output y is"):
        opt.proxy_targets(torch.zeros(2, 2), torch.tensor([[0.0, 0], [float("inf"), 0]]),
                          torch.zeros(2, 2))
