"""Model choice from Python (docs/config.md, "Model choice"): combabc.model_choice runs every
model of a [model_choice] config, and with exact=True enumerates them; the run's probabilities
agree with the exact ones within 4 Monte-Carlo errors (two tiny sensors, 2^6 configurations)."""

import os

import pytest

import combabc

CONFIG = """
[model.clamps]
per_edge = 3

[model.mesh]
elements_per_section = 2
elements_across_width = 2

[data]
csv = "data.csv"
position_column = "position_m"
displacement_column = "displacement_m"
position_unit = "m"
displacement_unit = "m"

[metric]
threshold = [4.0, 3.0, 2.4]
[[metric.component]]
type = "least_squares"
window = [0.31, 0.58]

[sampler]
waves = 3
accepted_per_wave = 300
seed = 5
threads = 1

[output]
directory = "out"

[model_choice]
[[model_choice.model]]
name = "clamped"
[[model_choice.model]]
name = "pinned"
model.clamps.fixed_support = "simply_supported"
"""


def test_model_choice_run_agrees_with_enumeration(tmp_path):
    with open(tmp_path / "data.csv", "w") as f:
        f.write("position_m,displacement_m\n")
        for i in range(31, 60, 3):
            f.write(f"{i / 100},{1.0 - abs(i / 100 - 0.45)}\n")
    (tmp_path / "run.toml").write_text(CONFIG)
    run = combabc._core.model_choice(str(tmp_path / "run.toml"))
    exact = combabc._core.model_choice(str(tmp_path / "run.toml"), exact=True)
    assert not run["exact"] and exact["exact"]
    assert [m["name"] for m in run["models"]] == ["clamped", "pinned"]
    for estimate, truth in zip(run["models"], exact["models"]):
        assert estimate["se"] > 0
        assert abs(estimate["probability"] - truth["probability"]) < 4 * estimate["se"]
        assert estimate["history"].endswith("history.sqlite")
    assert sum(m["probability"] for m in exact["models"]) == pytest.approx(1.0)
    # Each model's history is an ordinary run's.
    history = combabc.load_history(run["models"][1]["history"])
    assert len(history.waves) == 3
    # A model-choice config is not one run: combabc.run refuses it.
    with pytest.raises(combabc.Error, match="model_choice"):
        combabc.run(str(tmp_path / "run.toml"), output_directory=str(tmp_path / "plain"))


def test_public_model_choice_reads_back_the_tables(tmp_path):
    """combabc.model_choice and load_model_choice: the service's probabilities as a DataFrame by
    model, each model's history, and History.model_probabilities from a model's history."""
    with open(tmp_path / "data.csv", "w") as f:
        f.write("position_m,displacement_m\n")
        for i in range(31, 60, 3):
            f.write(f"{i / 100},{1.0 - abs(i / 100 - 0.45)}\n")
    (tmp_path / "run.toml").write_text(CONFIG.replace("accepted_per_wave = 300",
                                                      "accepted_per_wave = 100"))
    raw = combabc._core.model_choice(str(tmp_path / "run.toml"))
    # Again through the public wrapper: the finished models are read, not run again.
    table = combabc.model_choice(tmp_path / "run.toml")
    assert list(table.index) == ["clamped", "pinned"]
    assert table.attrs["reference"] == "clamped" and not table.attrs["exact"]
    for model in raw["models"]:
        row = table.loc[model["name"]]
        assert row["probability"] == pytest.approx(model["probability"], rel=1e-12)
        assert row["se"] == pytest.approx(model["se"], rel=1e-12)
        assert row["simulations"] == model["simulations"]
        assert os.path.samefile(row["history"], model["history"])
    assert table["probability"].sum() == pytest.approx(1.0)
    # The probabilities per wave (waves.csv): its last wave is the table's (both models reached
    # the final thresholds at their third wave).
    waves = table.attrs["waves"]
    assert list(waves["wave"].unique()) == [1, 2, 3]
    last = waves[waves["wave"] == 3].set_index("model")
    assert list(last["probability"]) == pytest.approx(list(table["probability"]), rel=1e-12)
    exact = combabc.model_choice(tmp_path / "run.toml", exact=True)
    assert exact.attrs["exact"] and (exact["se"] == 0).all()
    assert exact.attrs["waves"] is None  # one exact evidence per model, no waves
    # A model's History finds its model choice; a plain run's has none.
    history = combabc.load_history(table.loc["pinned", "history"])
    assert list(history.model_probabilities["probability"]) == list(table["probability"])
    assert combabc.load_history(exact.loc["pinned", "history"]).model_probabilities.attrs["exact"]
    assert combabc.load_history(exact.loc["pinned", "history"]).model_probabilities is not None
    with pytest.raises(FileNotFoundError, match="no model choice"):
        combabc.load_model_choice(tmp_path)


def test_joint_model_choice_agrees_with_enumeration(tmp_path):
    """method = "joint": one run over both models; the same exact probabilities within 4
    Monte-Carlo errors, every model's history the joint run's, and each model's bits."""
    with open(tmp_path / "data.csv", "w") as f:
        f.write("position_m,displacement_m\n")
        for i in range(31, 60, 3):
            f.write(f"{i / 100},{1.0 - abs(i / 100 - 0.45)}\n")
    (tmp_path / "run.toml").write_text(CONFIG.replace("[model_choice]\n",
                                                      "[model_choice]\nmethod = \"joint\"\n"))
    table = combabc.model_choice(tmp_path / "run.toml")
    exact = combabc.model_choice(tmp_path / "run.toml", exact=True)
    assert table.attrs["method"] == "joint" and exact.attrs["method"] == "enumeration"
    for name in ("clamped", "pinned"):
        row = table.loc[name]
        assert abs(row["probability"] - exact.loc[name, "probability"]) < 4 * row["se"]
        assert row["history"].endswith(os.path.join("joint", "history.sqlite"))
    bits = table.attrs["bits"]
    assert list(bits[bits["model"] == "pinned"]["bit"]) == [1, 2, 3, 4, 5, 6]
    history = combabc.load_history(table.loc["pinned", "history"])
    assert list(history.model_probabilities["probability"]) == list(table["probability"])
    # combabc.run is not the way to a model choice, whatever its method: it says which is.
    with pytest.raises(combabc.Error, match=r"has \[model_choice\].*combabc\.model_choice from"):
        combabc.run(tmp_path / "run.toml")


# Model choice over Problems: two deterministic linear simulators on 4 bits (16 configurations,
# prior 1/2 each), so each model's exact ABC evidence is Z_k = #{bits: |W_k bits - y| <= eps} / 16
# and P(M_k | y) = pi_k Z_k / sum_j pi_j Z_j, counted here by enumeration.
import itertools

import numpy as np

W_A = np.array([[1.0, 2.0, 0.0, 1.0], [0.0, 1.0, 3.0, 1.0]])
W_B = np.array([[3.0, 0.0, 1.0, 1.0], [1.0, 2.0, 1.0, 0.0]])
Y = np.array([2.0, 3.0])
EPS = 1.5  # no configuration of either model lies at exactly 1.5 from Y


def _problem(w):
    space = combabc.BinarySpace(dimension=4, default_prior_one=0.5)
    return combabc.Problem(space, lambda bits: bits.astype(float) @ w.T, observed=Y, batch=True)


def _options(seed=3):
    return combabc.make_options(num_waves=2, accepted_per_wave=300, seed=seed, threads=1,
                                thresholds=[3.0, EPS])


def _exact(priors, ws):
    z = []
    for w in ws:
        d = [np.linalg.norm(w @ np.array(b, dtype=float) - Y)
             for b in itertools.product((0, 1), repeat=4)]
        assert min(abs(x - EPS) for x in d) > 1e-6
        z.append(sum(x <= EPS for x in d) / 16)
    total = sum(p * v for p, v in zip(priors, z))
    return [p * v / total for p, v in zip(priors, z)]


def test_model_choice_over_problems_agrees_with_enumeration(tmp_path):
    options = _options()
    table = combabc.model_choice({"a": _problem(W_A), "b": _problem(W_B)}, options,
                                 priors={"a": 0.3, "b": 0.7}, output_directory=tmp_path)
    assert list(table.index) == ["a", "b"] and options.seed == 3
    exact = _exact([0.3, 0.7], [W_A, W_B])  # Z_a = 6/16, Z_b = 4/16: P(a | y) = 0.39
    for name, truth, prior in zip(["a", "b"], exact, [0.3, 0.7]):
        # The data move the probability away from the prior by more than the test's tolerance.
        assert abs(truth - prior) > 4 * table.loc[name, "se"] > 0
        assert abs(table.loc[name, "probability"] - truth) < 4 * table.loc[name, "se"]
        assert table.loc[name, "reached"]
    assert table.attrs["method"] == "evidence"
    # Each model's history, on seed + k, in models/<name>/; read back as a config's model choice.
    history = combabc.load_history(table.loc["b", "history"])
    assert history.path == str(tmp_path / "models" / "b" / "history.sqlite")
    assert list(history.model_probabilities.index) == ["a", "b"]
    assert combabc.load_model_choice(tmp_path)["probability"].tolist() == \
        table["probability"].tolist()


def test_identical_problems_give_the_prior_ratio(tmp_path):
    table = combabc.model_choice([("same", _problem(W_A), 0.25), ("again", _problem(W_A), 0.75)],
                                 _options(seed=8), output_directory=tmp_path)
    assert table.loc["same", "se"] > 0
    assert abs(table.loc["same", "probability"] - 0.25) < 4 * table.loc["same", "se"]


def test_model_choice_over_problems_refuses_before_running(tmp_path):
    a, b = _problem(W_A), _problem(W_B)
    with pytest.raises(combabc.Error, match="priors sum to 0.9; they must sum to 1"):
        combabc.model_choice({"a": a, "b": b}, _options(), priors=[0.4, 0.5],
                             output_directory=tmp_path)
    with pytest.raises(combabc.Error, match="not a valid model name"):
        combabc.model_choice({"a/b": a, "b": b}, _options(), output_directory=tmp_path)
    with pytest.raises(combabc.Error, match='model "a" is given twice'):
        combabc.model_choice([("a", a), ("a", b)], _options(), output_directory=tmp_path)
    adaptive = _options()
    adaptive.thresholds = [combabc.ThresholdSchedule()]
    with pytest.raises(combabc.Error, match="no final threshold"):
        combabc.model_choice({"a": a, "b": b}, adaptive, output_directory=tmp_path)
    named = combabc.Problem(b.space, b.simulator, observed=Y, batch=True,
                            distance=lambda out, y: np.abs(out - y).sum(axis=1))
    with pytest.raises(ValueError, match="components"):
        combabc.model_choice({"a": a, "b": named}, _options(), output_directory=tmp_path)
    other = combabc.Problem(b.space, b.simulator, observed=Y + 1, batch=True)
    with pytest.raises(ValueError, match="observed data differ"):
        combabc.model_choice({"a": a, "b": other}, _options(), output_directory=tmp_path)
    with pytest.raises(ValueError, match="output_directory"):
        combabc.model_choice({"a": a, "b": b}, _options())
    assert not os.listdir(tmp_path)  # nothing ran
