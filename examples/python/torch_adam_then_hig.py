"""A torch network learns controls through a badly scaled differentiable simulator: Adam first,
then physgrad's HIG on the per-sample Jacobian (batched autodiff, the chunk chosen from memory).

    PYTHONPATH=build/python /usr/bin/python3 examples/python/torch_adam_then_hig.py [--quick]
"""

import argparse

import torch

import physgrad.torch as pt

LAMBDA = 0.01  # the second output is a hundred times less sensitive


def simulate(c):
    """y = (sin c₁, λ·c₂ + c₁²/4): a differentiable torch "physics" with one badly scaled output."""
    return torch.stack([torch.sin(c[:, 0]), LAMBDA * c[:, 1] + 0.25 * c[:, 0] ** 2], dim=1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--quick", action="store_true")
    args = parser.parse_args()
    adam_steps, hig_steps = (100, 15) if args.quick else (1000, 100)

    torch.manual_seed(0)
    inputs = torch.linspace(-1, 1, 64, dtype=torch.float64).unsqueeze(1)
    wanted = torch.cat([0.8 * torch.sin(3 * inputs), torch.cos(2 * inputs)], dim=1)
    targets = simulate(wanted)
    loss_fn = lambda y, t: 0.5 * ((y - t) ** 2).sum(dim=1).mean()
    model = torch.nn.Sequential(torch.nn.Linear(1, 32), torch.nn.Tanh(),
                                torch.nn.Linear(32, 2)).double()

    def loss():
        return loss_fn(simulate(model(inputs)), targets)

    print(f"start: loss {loss().item():.3e}")
    adam = torch.optim.Adam(model.parameters(), lr=1e-2)
    for _ in range(adam_steps):
        adam.zero_grad()
        value = loss()
        value.backward()
        adam.step()
    after_adam = loss().item()
    print(f"after {adam_steps} Adam steps: loss {after_adam:.3e}")

    hig = pt.HIG(model.parameters(), lr=0.5, rcond=1e-6)
    closure = pt.jacobian_closure(model, simulate, loss_fn, inputs, targets)
    for _ in range(hig_steps):
        hig.step(closure)
    after_hig = loss().item()
    print(f"after {hig_steps} HIG steps: loss {after_hig:.3e} "
          f"(last step: rank {hig.last_info['rank']}, {hig.last_info['backend']} path)")
    if not after_hig < after_adam:
        raise SystemExit("HIG did not lower the loss Adam left")


if __name__ == "__main__":
    main()
