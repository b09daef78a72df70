"""The structured rules from torch on a small 1-D CNN where exact HIG is affordable.

A heat-inverse task: the network maps an observed final temperature y* (32 cells, periodic) to
an initial state x, the simulator diffuses it (FFT, exp(−D k²) per mode), loss ½‖P(f(y*)) − y*‖²
averaged over the batch. Prints (1) the cosine of each structured update (KFAC, KFACHIG,
LanczosGN, LanczosHIG) to the exact one (GN for κ = 1, HIG for κ = ½) at initialisation and
after 200 Adam steps, and (2) the test loss after N updates of every rule and of Adam, and of
Adam given the same seconds as the rule took.
Usage: torch_structured_cnn.py [N] [seed]   (--quick: N = 3, 10 Adam steps)
"""

import copy
import sys
import time

import torch

import physgrad.torch as pt

CELLS, BATCH, CHANNELS = 32, 32, 16
torch.set_default_dtype(torch.float64)


def simulate(x):
    modes = torch.fft.rfftfreq(CELLS, 1.0 / CELLS)
    return torch.fft.irfft(torch.fft.rfft(x.reshape(x.shape[0], CELLS)) *
                           torch.exp(-7e-4 * (2 * torch.pi * modes) ** 2 / 4), n=CELLS)


def make_model(seed):
    torch.manual_seed(seed)
    conv = lambda i, o: torch.nn.Conv1d(i, o, 5, padding=2, padding_mode="circular")  # noqa
    return torch.nn.Sequential(conv(1, CHANNELS), torch.nn.Tanh(), conv(CHANNELS, CHANNELS),
                               torch.nn.Tanh(), conv(CHANNELS, CHANNELS), torch.nn.Tanh(),
                               conv(CHANNELS, 1), torch.nn.Flatten())


def make_data(count, seed):
    generator = torch.Generator().manual_seed(seed)
    grid = torch.arange(CELLS) * 2 * torch.pi / CELLS
    x = sum(torch.randn(count, 1, generator=generator) / (k + 1) *
            torch.sin(k * grid + 6 * torch.rand(count, 1, generator=generator))
            for k in range(1, 9))
    targets = simulate(x)
    return targets.unsqueeze(1), targets


def loss_fn(y, t):
    return 0.5 * ((y - t) ** 2).sum(1).mean()


def direction(cls, model, inputs, targets, **options):
    """The rule's update Δθ (lr 1) at the model's θ on one batch; θ left as it was."""
    other = copy.deepcopy(model)
    before = torch.cat([p.detach().reshape(-1) for p in other.parameters()])
    if cls in (pt.HIG, pt.GN):
        cls(other.parameters(), **options).step(
            pt.jacobian_closure(other, simulate, loss_fn, inputs, targets))
    else:
        cls(other.parameters(), other, **options).step(
            pt.structured_closure(other, simulate, loss_fn, inputs, targets))
    return torch.cat([p.detach().reshape(-1) for p in other.parameters()]) - before


def cosines(model, inputs, targets):
    exact = {1.0: direction(pt.GN, model, inputs, targets),
             0.5: direction(pt.HIG, model, inputs, targets)}
    out = {}
    for name, cls, kappa in (("KFAC", pt.KFAC, 1.0), ("KFACHIG", pt.KFACHIG, 0.5),
                             ("LanczosGN", pt.LanczosGN, 1.0),
                             ("LanczosHIG", pt.LanczosHIG, 0.5)):
        d = direction(cls, model, inputs, targets)
        out[name] = float(d @ exact[kappa] / (d.norm() * exact[kappa].norm()))
    return out


def train(make_opt, model, data, updates, seconds=None):
    """Test loss after `updates` updates (or after `seconds`), and the seconds taken."""
    opt, structured = make_opt(model)
    (train_x, train_y), (test_x, test_y) = data
    start, done = time.perf_counter(), 0
    while done < updates and (seconds is None or time.perf_counter() - start < seconds):
        k = done % (train_x.shape[0] // BATCH)
        x, t = train_x[k * BATCH:(k + 1) * BATCH], train_y[k * BATCH:(k + 1) * BATCH]
        if structured is None:
            opt.zero_grad()
            loss = loss_fn(simulate(model(x)), t)
            loss.backward()
            opt.step()
        else:
            opt.step(structured(model, simulate, loss_fn, x, t))
        done += 1
    elapsed = time.perf_counter() - start
    with torch.no_grad():
        return float(loss_fn(simulate(model(test_x)), test_y)), elapsed, done


def rules():
    jac, st = pt.jacobian_closure, pt.structured_closure
    return {"HIG": lambda m: (pt.HIG(m.parameters(), lr=LR["HIG"]), jac),
            "GN": lambda m: (pt.GN(m.parameters(), lr=LR["GN"]), jac),
            "KFAC": lambda m: (pt.KFAC(m.parameters(), m, lr=LR["KFAC"]), st),
            "KFACHIG": lambda m: (pt.KFACHIG(m.parameters(), m, lr=LR["KFACHIG"]), st),
            "LanczosGN": lambda m: (pt.LanczosGN(m.parameters(), m, lr=LR["LanczosGN"]), st),
            "LanczosHIG": lambda m: (pt.LanczosHIG(m.parameters(), m, lr=LR["LanczosHIG"]), st)}


LR = {}


def main():
    args = [a for a in sys.argv[1:] if a != "--quick"]
    quick = "--quick" in sys.argv[1:]
    updates = 3 if quick else int(args[0]) if args else 100
    seed = int(args[1]) if len(args) > 1 else 0
    warmup = 10 if quick else 200
    data = (make_data(8 * BATCH, seed), make_data(256, seed + 1))
    model = make_model(seed)
    print(f"1-D CNN, {sum(p.numel() for p in model.parameters())} weights, {CELLS} cells, "
          f"batch {BATCH}, seed {seed}")
    x, t = data[0][0][:BATCH], data[0][1][:BATCH]
    at_init = cosines(model, x, t)
    adam_model = copy.deepcopy(model)
    adam = lambda m: (torch.optim.Adam(m.parameters(), lr=1e-3), None)  # noqa: E731
    train(adam, adam_model, data, warmup)
    after = cosines(adam_model, x, t)
    print("\ncosine to the exact update (GN for κ = 1, HIG for κ = ½), lr 1, one batch")
    print(f"{'rule':<11} {'at init':>8} {'after ' + str(warmup) + ' Adam':>15}")
    for name in at_init:
        print(f"{name:<11} {at_init[name]:8.4f} {after[name]:15.4f}")
    # The step size of each rule: the best of five on a short run (a fifth of the updates).
    for name, make in rules().items():
        trials = {}
        for lr in (0.01, 0.03, 0.1, 0.3, 1.0):
            LR[name] = lr
            trials[lr] = train(make, copy.deepcopy(model), data, max(1, updates // 5))[0]
        LR[name] = min(trials, key=lambda lr: trials[lr] if trials[lr] == trials[lr]
                       else float("inf"))
    adam_loss, adam_seconds, _ = train(adam, copy.deepcopy(model), data, updates)
    print(f"\ntest loss after {updates} updates (initial "
          f"{train(adam, copy.deepcopy(model), data, 0)[0]:.4g})")
    print(f"{'rule':<11} {'lr':>4} {'loss':>10} {'seconds':>8} {'Adam same s':>12} "
          f"{'Adam updates':>13}")
    print(f"{'Adam':<11} {'1e-3':>4} {adam_loss:10.4g} {adam_seconds:8.2f} {'':>12} {'':>13}")
    for name, make in rules().items():
        loss, seconds, _ = train(make, copy.deepcopy(model), data, updates)
        same, _, count = train(adam, copy.deepcopy(model), data, 10 ** 9, seconds=seconds)
        print(f"{name:<11} {LR[name]:4g} {loss:10.4g} {seconds:8.2f} {same:12.4g} {count:13d}")


if __name__ == "__main__":
    main()
