# One LearningExperiment object run from several Python threads at once: each thread gets the
# exception its own callbacks raised, none is lost or raised in another thread.
import threading

import numpy as np

import physgrad


class RaisesInItsThread:
    name = "raises"

    def forward(self, y):
        if y.ndim == 1 and abs(y[0]) > 0:  # not the size probe at construction (y = 0)
            raise KeyError(f"raised in {threading.current_thread().name}")
        return y


def points(count, seed):
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2))
    return x, x


def test_each_thread_gets_its_own_exception(tmp_path):
    own = physgrad.LearningExperiment("own", "", RaisesInItsThread(), [2, 4, 2], points,
                                      iterations=5, train_size=8, test_size=4)
    caught = {}

    def run(index):
        try:
            physgrad.run_experiment("own", {"optimizers": "adam"}, str(tmp_path / str(index)),
                                    progress=None, experiments=[own])
            caught[index] = None
        except BaseException as e:  # noqa: B902 (what was raised is what is checked)
            caught[index] = e

    for _ in range(5):
        caught.clear()
        threads = [threading.Thread(target=run, args=(i,), name=f"runner-{i}") for i in range(3)]
        for t in threads:
            t.start()
        for t in threads:
            t.join()
        for i in range(3):
            assert isinstance(caught[i], KeyError), (i, repr(caught[i]))
            assert f"raised in runner-{i}" in str(caught[i]), (i, str(caught[i]))
