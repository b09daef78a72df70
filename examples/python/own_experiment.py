"""A script's own learning experiment through physgrad's experiment framework: a 2 → 16 → 2
network learns the inverse of the simulator P(y) = y³ (elementwise), trained through P with
L = ½‖P(f(x)) − x‖², by Adam and by HIG; run folders, checkpoints, resume and the index as for
the reference experiments.

    PYTHONPATH=build/python /usr/bin/python3 examples/python/own_experiment.py ARGUMENTS
    … run DIR [--NAME VALUE …]   a new run (options as `physgrad run`)
    … resume DIR                 continues an unfinished run (killed, or stopped with Ctrl-C,
                                 which keeps its checkpoint and prints the resume command)
    … report DIR                 DIR/index.html over the run folders in DIR
    … --quick                    a short run into a temporary folder
"""
import sys
import tempfile

import numpy as np

import physgrad


class Cube:
    """P(y) = y³ elementwise, with its Jacobian diag(3y²)."""

    name = "cube"
    output_dim = 2

    def forward(self, y):
        return y ** 3

    def jacobian(self, y):
        return np.diag(3 * y ** 2)


def points(count, seed):
    """count points x uniform in [−1, 1]²: the network's inputs and the targets P(f(x)) should
    reach."""
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2))
    return x, x


CUBE_ROOT = physgrad.LearningExperiment(
    "cube-root", "a 2 -> 16 -> 2 network learns the inverse of P(y) = y^3", Cube(), [2, 16, 2],
    points, optimizers=["adam", "hig"], iterations=200,
    rules={"adam": {"lr": 0.01, "batch": 64}, "hig": {"lr": 1.0, "batch": 64}})


def print_finals(outcome):
    if not outcome.finished:
        print(outcome.stopped)
        return
    for run in outcome.summary["runs"]:
        print(f"{run['label']:<6} final test loss {run['final']['test_loss']:.6e}")
    print("report:", outcome.report)


def main(args):
    if args == ["--quick"]:
        with tempfile.TemporaryDirectory() as folder:
            print_finals(physgrad.run_experiment("cube-root", {"iters": 20}, folder + "/run",
                                                 progress=None, experiments=[CUBE_ROOT]))
        return 0
    if len(args) < 2 or len(args) % 2 != 0:
        print(__doc__, file=sys.stderr)
        return 2
    command, folder, rest = args[0], args[1], args[2:]
    if command == "run":
        options = {name.removeprefix("--"): value for name, value in zip(rest[::2], rest[1::2])}
        print_finals(physgrad.run_experiment("cube-root", options, folder, progress=None,
                                             experiments=[CUBE_ROOT]))
    elif command == "resume":
        print_finals(physgrad.resume_experiment(folder, progress=None, experiments=[CUBE_ROOT]))
    elif command == "report":
        index = physgrad.write_index(folder, experiments=[CUBE_ROOT])
        print(f"{index['folders']} run folders: {index['page']}")
    else:
        print(f"unknown command {command!r} (known: run, resume, report)", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":
    try:
        sys.exit(main(sys.argv[1:]))
    except KeyboardInterrupt as stopped:  # Ctrl-C: the run stopped in order, its checkpoint kept
        print(stopped)
        if len(sys.argv) > 2:
            print(f"or: {sys.argv[0]} resume {sys.argv[2]}")
        sys.exit(130)
