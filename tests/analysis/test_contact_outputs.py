"""Outputs that read a run's contacts (``{contact: <name>.force}``, ``.impulse``): the
normal force of a held contact and the impulses of its events, against the closed forms of
the bouncing ball (models/contact/bouncing_ball.yaml)."""

from pathlib import Path

import numpy as np
import pytest

import mbsynth as mb
from mbsynth.core.errors import ModelError

MODEL = (Path(__file__).resolve().parents[2] / "models" / "contact" / "bouncing_ball.yaml").read_text()
M, R, G, H0, E = 0.2, 0.05, 9.81, 1.0, 0.5


def _ball(outputs):
    return mb.loads(MODEL + "outputs:\n" + "".join(f"  {name}: {spec}\n" for name, spec in outputs.items()))


def test_the_ball_reads_its_impulses_at_each_bounce_and_its_weight_once_at_rest(tmp_path):
    """Impact k has the impulse m (1 + e) v_k, v_k = e^k g t1; from the accumulation point
    t1 (1 + 2e/(1 − e)) on the ball rests: the floor pushes with m g."""
    system = _ball({"push": "{contact: floor.force}", "hits": "{contact: floor.impulse}"})
    out = tmp_path / "ball.npz"
    traj = mb.simulate(system, 2.0, dt=0.01, out=out, rtol=1e-12, atol=1e-12)
    push, hits = traj.column("push"), traj.column("hits")
    t1 = np.sqrt(2 * (H0 - R) / G)
    impacts = [ev for ev in traj.events if ev.kind == "impact"]
    for k, ev in enumerate(impacts[:4]):
        expected = M * (1 + E) * E**k * G * t1
        row = int(np.searchsorted(traj.t, ev.t))  # the first row at or after the impact
        assert hits[row] == pytest.approx(expected, rel=1e-9)
    assert hits.sum() == pytest.approx(sum(ev.impulse for ev in traj.events if ev.kind in ("impact", "contact")),
                                       rel=1e-12)
    rest = t1 * (1 + 2 * E / (1 - E))
    assert (push[traj.t < t1] == 0).all()
    assert np.abs(push[traj.t > rest + 0.05] - M * G).max() < 1e-9
    saved = np.load(out)
    assert np.array_equal(saved["outputs"][:, list(saved["output_names"]).index("push")], push)


@pytest.mark.parametrize("spec, message", [
    ("{contact: wall.force}", "outputs.push.contact: unknown contact or limit 'wall' in 'wall.force'"),
    ("{contact: floor.torque}", "outputs.push.contact: output 'push': a contact output is '<contact>.force', "
                                "'.impulse' or '.friction', not '.torque'"),
])
def test_a_contact_output_of_an_unknown_contact_or_part_is_refused_at_its_line(spec, message):
    with pytest.raises(ModelError) as err:
        _ball({"push": spec})
    assert message in str(err.value)


def test_a_block_sliding_down_a_slope_reads_the_normal_force_m_g_cos_alpha():
    """models/contact/block_on_slope.yaml, held from the start and sliding (μ = 0.3 <
    tan 0.5): the plane pushes with m g cos α at every row after the first (the first row is
    recorded before the run settles its contacts at t0, whose impulse the next row reads)."""
    text = (Path(__file__).resolve().parents[2] / "models" / "contact" / "block_on_slope.yaml").read_text()
    system = mb.loads(text + "outputs:\n  push: {contact: floor.force}\n  hits: {contact: floor.impulse}\n")
    traj = mb.simulate(system, 0.5, dt=0.05, rtol=1e-10, atol=1e-10)
    assert np.abs(traj.column("push")[1:] - 2.0 * G * np.cos(0.5)).max() < 1e-9
    assert (traj.column("hits") == 0).all()  # it came to rest in contact at t0 from rest: no impulse



@pytest.mark.parametrize("alpha, mu, size", [
    (0.5, 0.3, lambda m, a, mu: mu * m * G * np.cos(a)),  # tan α > μ: it slides, friction μ N
    (0.2, 0.3, lambda m, a, mu: m * G * np.sin(a)),  # tan α < μ: it sticks, friction m g sin α
])
def test_the_friction_output_of_a_block_on_a_slope_is_mu_N_sliding_and_m_g_sin_alpha_sticking(alpha, mu, size):
    """``{contact: floor.friction}`` (models/contact/block_on_slope.yaml, m = 2): the
    friction force in the world, up the slope (−cos α, 0, sin α), of size μ m g cos α = μ N
    while the block slides and m g sin α while it sticks, at every row after the first."""
    text = (Path(__file__).resolve().parents[2] / "models" / "contact" / "block_on_slope.yaml").read_text()
    system = mb.loads(text + "outputs:\n  drag: {contact: floor.friction}\n  push: {contact: floor.force}\n",
                      parameters={"alpha": alpha, "mu": mu})
    traj = mb.simulate(system, 0.5, dt=0.05, rtol=1e-10, atol=1e-10)
    drag = np.column_stack([traj.column(f"drag[{x}]") for x in "xyz"])[1:]
    assert np.abs(drag - size(2.0, alpha, mu) * np.array([-np.cos(alpha), 0.0, np.sin(alpha)])).max() < 1e-10
    if alpha > np.arctan(mu):
        assert np.abs(np.linalg.norm(drag, axis=1) - mu * traj.column("push")[1:]).max() < 1e-10
