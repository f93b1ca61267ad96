"""The examples of issue 19 run end to end (they are the README's joint-space tour): the
UR5 drawing a circle, its servo multipliers against Pinocchio's rnea, and the
PD-controlled UR5 holding a payload, its PD torques against the torques of inverse statics."""

import importlib.util
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def example(name):
    spec = importlib.util.spec_from_file_location(name, EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def test_ur5_circle_torques_equal_rnea(tmp_path):
    """Inverse dynamics by constraints: the servo multipliers along the drawn circle are the
    joint torques of pin.rnea on the same joint trajectory."""
    assert example("ur5_circle").main(str(tmp_path / "circle.png")) < 1e-9
    assert (tmp_path / "circle.png").stat().st_size > 10_000


def test_pd_arm_comes_to_rest_where_its_torques_hold_it(tmp_path):
    """After 4 s of sampled PD control the UR5 rests where the PD torques equal the static
    torques read off servo rows (inverse statics); the payload's remaining swing on its
    undamped spring keeps them apart by about 1 %."""
    assert example("pd_arm_payload").main(str(tmp_path / "pd.png")) < 0.03
    assert (tmp_path / "pd.png").stat().st_size > 10_000
