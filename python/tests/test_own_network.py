# A script's own experiment with a convolutional network (physgrad.LearningExperiment's
# `network`): a U-net trained by Adam and HIG, a plain convolution stack, and every mistake in the
# network's options refused in one line before anything runs.
import json

import numpy as np
import pytest

import physgrad

N = 8  # cells per axis: 8×8 fields of 64 values


class Smooth:
    """P(y) = 0.6·y + 0.2·(y shifted by ±1), a linear map with eigenvalues in [0.2, 1]."""

    name = "smooth"

    def __init__(self, size=N * N):
        eye = np.eye(size)
        self.matrix = 0.6 * eye + 0.2 * (np.roll(eye, 1, axis=1) + np.roll(eye, -1, axis=1))

    def forward(self, y):
        return self.matrix @ y

    def jacobian(self, y):
        return self.matrix


def fields(count, seed):
    """Random 8×8 fields: the network's inputs and the targets P(f(x)) should reach."""
    x = np.random.default_rng(seed).uniform(-1, 1, size=(count, N * N))
    return x, x


UNET = {"kind": "unet", "dims": 2, "n": N, "levels": 2, "filters": 2, "batch_norm": False}


def experiment(network=UNET, name="own-unet", simulator=None, data=fields, **kw):
    kw.setdefault("rules", {"adam": {"lr": 0.01, "batch": 16}, "hig": {"batch": 16}})
    return physgrad.LearningExperiment(name, "a U-net learns the inverse of a smoothing",
                                       simulator or Smooth(), data=data, network=network,
                                       iterations=30, train_size=32, test_size=16, **kw)


def test_a_unet_trained_by_adam_and_hig_lowers_the_loss(tmp_path):
    out = tmp_path / "u"
    result = physgrad.run_experiment("own-unet", {"optimizers": ["adam", "hig"]}, str(out),
                                     progress=None, experiments=[experiment()])
    assert result.finished
    metrics = physgrad.open_metrics(result.folder)
    optimizers = np.array(metrics["optimizer"])
    for rule in ("adam", "hig"):
        test_loss = metrics["test_loss"][optimizers == rule]
        test_loss = test_loss[np.isfinite(test_loss)]
        assert len(test_loss) > 2, rule
        assert test_loss[-1] < 0.95 * test_loss[0], (rule, test_loss)
    # HIG, a Jacobian rule, runs on the U-net's per-sample gradient rows and goes much further.
    hig = metrics["test_loss"][optimizers == "hig"]
    hig = hig[np.isfinite(hig)]
    assert hig[-1] < 0.5 * hig[0], hig
    networks = json.loads((out / "networks.json").read_text())["networks"]
    assert len(networks) == 2
    for entry in networks:
        described = entry["network"]
        assert described["kind"] == "unet"
        assert (described["levels"], described["filters"], described["batch_norm"]) == (2, 2, False)
        assert described["input_dim"] == described["output_dim"] == N * N
        assert len(entry["parameters"]) == described["parameters"]


def test_channels_set_the_sizes_of_the_data_and_the_simulator(tmp_path):
    # A 1-D stack of 2 input channels to 1 output channel on 8 cells: the data's inputs have
    # 2·8 values, the simulator's inputs 8.
    def two_channels(count, seed):
        x = np.random.default_rng(seed).uniform(-1, 1, size=(count, 2 * N))
        return x, x[:, :N] - x[:, N:]

    stack = {"kind": "conv", "dims": 1, "n": N, "channels": [2, 4, 1], "padding": "periodic"}
    own = experiment(stack, "own-conv", Smooth(N), two_channels, rules={})
    result = physgrad.run_experiment("own-conv", {"optimizers": "adam", "iters": 5},
                                     str(tmp_path / "c"), progress=None, experiments=[own])
    assert result.finished
    [entry] = json.loads((tmp_path / "c" / "networks.json").read_text())["networks"]
    assert entry["network"]["kind"] == "conv_stack"
    assert (entry["network"]["input_dim"], entry["network"]["output_dim"]) == (2 * N, N)
    wrong = experiment(stack, "own-conv", Smooth(N), fields, rules={})
    with pytest.raises(physgrad.Error, match=r"inputs \(32, 64\).*expected \(32, 16\)"):
        physgrad.run_experiment("own-conv", {"optimizers": "adam", "iters": 5},
                                str(tmp_path / "w"), progress=None, experiments=[wrong])
    assert not (tmp_path / "w").exists()


@pytest.mark.parametrize("change, match", [
    ({"filers": 2}, r"network: unknown key 'filers'"),
    ({"levels": 0}, r"network\['levels'\] is 0, expected an integer in \[1, 8\]"),
    ({"levels": 3, "n": 6}, r"network\['n'\] is 6, not a multiple of 4"),
    ({"filters": "8"}, r"network\['filters'\] is '8', expected an integer"),
    ({"filters": 2.0}, r"network\['filters'\] is 2.0, expected an integer"),
    ({"dims": 3}, r"network\['dims'\] is 3"),
    ({"batch_norm": "yes"}, r"network\['batch_norm'\] is 'yes', expected True or False"),
    ({"padding": "reflect"}, r"network\['padding'\] is 'reflect', expected one of zero, periodic"),
    ({"activation": "gelu"}, r"network\['activation'\] is 'gelu', expected one of relu"),
    ({"kind": "mlp"}, r"network\['kind'\] is 'mlp', expected one of unet, conv"),
    ({"n": None}, r"network\['n'\] is None, expected an integer"),
    ({"n": 2048}, r"network\['n'\] is 2048: 2048×2048 = 4194304 cells, more than 1048576"),
])
def test_a_bad_network_option_is_refused_naming_it(change, match):
    with pytest.raises(physgrad.Error, match=match) as raised:
        experiment(dict(UNET, **change))
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize("network, match", [
    ({"n": 8}, r"network needs 'kind'"),
    ({"kind": "unet"}, r"network needs 'n'"),
    ({"kind": "conv", "n": 8, "channels": [1]},
     r"network\['channels'\] is \[1\], expected at least 2"),
    ({"kind": "conv", "n": 8, "channels": [1, 1], "kernel": 2}, r"network\['kernel'\] is 2"),
    ({"kind": "conv", "n": 8, "channels": [1, 1], "levels": 2}, r"network: unknown key 'levels'"),
    ({"kind": "unet", "n": 8, 3: 1}, r"network key 3 is not a string"),
    ([1, 2], r"network is \[1, 2\], expected a dict"),
])
def test_a_missing_or_misplaced_key_is_refused(network, match):
    with pytest.raises(physgrad.Error, match=match) as raised:
        experiment(network)
    assert "\n" not in str(raised.value)


def test_widths_or_network_exactly_one():
    with pytest.raises(physgrad.Error, match="give widths .* or network .*, not both"):
        physgrad.LearningExperiment("b", "", Smooth(), [64, 64], fields, network=UNET)
    with pytest.raises(physgrad.Error, match="give widths .* or network"):
        physgrad.LearningExperiment("n", "", Smooth(), data=fields)
    # widths stays the fourth argument, as before.
    assert physgrad.LearningExperiment("w", "", Smooth(), [64, 64], fields).name == "w"


def test_batch_norm_refuses_the_jacobian_rules_naming_them(tmp_path):
    normed = dict(UNET, batch_norm=True)
    with pytest.raises(physgrad.Error, match=r"optimizers: 'hig' needs per-sample Jacobians.*"
                                             r"batch_norm=False") as raised:
        experiment(normed)  # adam and hig, the default optimizers
    assert "\n" not in str(raised.value)
    own = experiment(normed, optimizers=["adam"])
    with pytest.raises(physgrad.Error, match=r"--optimizers: 'gn' needs per-sample Jacobians.*"
                                             r"batch_norm=False"):
        physgrad.run_experiment("own-unet", {"optimizers": ["adam", "gn"]}, str(tmp_path / "g"),
                                progress=None, experiments=[own])
    assert not (tmp_path / "g").exists()
    # Adam trains it: batch norm with the batch's statistics.
    result = physgrad.run_experiment("own-unet", {"optimizers": "adam", "iters": 3},
                                     str(tmp_path / "a"), progress=None, experiments=[own])
    assert result.finished
    [entry] = json.loads((tmp_path / "a" / "networks.json").read_text())["networks"]
    assert entry["network"]["batch_norm"] is True


def test_a_resume_with_a_changed_network_is_refused(tmp_path):
    physgrad.run_experiment("own-unet", {"optimizers": "adam", "iters": 3},
                            str(tmp_path / "whole"), progress=None, experiments=[experiment()])
    # A run stopped before it started: its config.json alone, as Run::start wrote it.
    stopped = tmp_path / "stopped"
    stopped.mkdir()
    (stopped / "config.json").write_text((tmp_path / "whole" / "config.json").read_text())
    for changed in (dict(UNET, filters=3), dict(UNET, padding="periodic")):
        with pytest.raises(physgrad.Error, match="definition changed.*network") as raised:
            physgrad.resume_experiment(str(stopped), progress=None,
                                       experiments=[experiment(changed)])
        assert "\n" not in str(raised.value)
    with pytest.raises(physgrad.Error, match="definition changed.*widths none → 64,64"):
        physgrad.resume_experiment(str(stopped), progress=None, experiments=[
            physgrad.LearningExperiment("own-unet", "", Smooth(), [64, 64], fields)])
    # The defaults filled in are part of the definition: the same network, spelt out, resumes.
    spelt_out = dict(UNET, in_channels=1, out_channels=1, activation="relu", padding="zero")
    assert physgrad.resume_experiment(str(stopped), progress=None,
                                      experiments=[experiment(spelt_out)]).finished


def test_the_kronecker_factored_rules_train_a_unet_without_batch_norm(tmp_path):
    # A ConvNetwork gives each convolution's Kronecker factors (spatial positions as samples);
    # with batch norm they are refused as every rule needing per-sample cotangents is.
    rules = {"kfac-hig": {"batch": 16, "lr": 0.1, "refresh": 1}}
    result = physgrad.run_experiment("own-unet", {"optimizers": ["kfac-hig"], "iters": 5},
                                     str(tmp_path / "k"), progress=None,
                                     experiments=[experiment(rules=rules)])
    assert result.finished
    with pytest.raises(physgrad.Error, match=r"optimizers: 'kfac' needs per-sample Jacobians"):
        experiment(dict(UNET, batch_norm=True), optimizers=["adam", "kfac"])


class Interrupting(Smooth):
    """Smooth, whose forward raises KeyboardInterrupt once, at its call number `at` (as Ctrl-C
    arriving there would)."""

    def __init__(self, at=None):
        super().__init__()
        self.calls, self.at = 0, at

    def forward(self, y):
        self.calls += 1
        if self.calls == self.at:
            raise KeyboardInterrupt
        return super().forward(y)


def test_a_stopped_unet_run_resumes_to_the_uninterrupted_result(tmp_path):
    options = {"optimizers": ["adam", "hig"], "checkpoint-every": 5}
    whole = physgrad.run_experiment("own-unet", options, str(tmp_path / "whole"), progress=None,
                                    experiments=[experiment(simulator=Interrupting())])
    part = str(tmp_path / "part")
    with pytest.raises(KeyboardInterrupt, match="resume_experiment"):
        physgrad.run_experiment("own-unet", options, part, progress=None,
                                experiments=[experiment(simulator=Interrupting(at=300))])
    assert (tmp_path / "part" / "checkpoint.pgc").exists()
    assert not (tmp_path / "part" / "summary.json").exists()
    resumed = physgrad.resume_experiment(part, progress=None,
                                         experiments=[experiment(simulator=Interrupting())])
    assert resumed.finished
    finals = [[run["final"]["test_loss"] for run in outcome.summary["runs"]]
              for outcome in (whole, resumed)]
    assert finals[0] == finals[1]
    networks = [json.loads((tmp_path / name / "networks.json").read_text())
                for name in ("whole", "part")]
    assert networks[0] == networks[1]  # every θ bit for bit
