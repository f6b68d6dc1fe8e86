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
