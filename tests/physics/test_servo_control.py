"""The servo law on a closed-form loop: one sphere pressed between a floor and a servo lid.

With linear contacts of stiffness k on both sides the lid sees a bed of stiffness K = k / 2.
When the floor rises at a constant speed v, the lid has to retreat at v to hold its target
force F. A proportional servo (v = gain x error) can only do that with a standing error:
its load settles at F + v / gain. The integral term removes it: the load settles at F and the
integrated error at I = -v / integral_gain (the retreat speed it commands). In steady state the
sphere moves with both walls, so no dashpot force enters these values.
"""

from __future__ import annotations

import numpy as np
import pytest

import grainscale as gs

R = 1e-3  # m
K_CONTACT = 1e4  # N/m, each side
FORCE = 0.1  # N, the lid's target
FLOOR_SPEED = 1e-3  # m/s
GAIN = 0.2  # (m/s)/N: K gain = 1000 1/s
MAT = gs.Material(density=2500.0, youngs_modulus=1e8, poisson_ratio=0.3)


def sandwich(
    integral_gain: float, floor_speed: float, gap: float = 0.0, max_speed: float = 0.05
) -> tuple[gs.Simulation, int]:
    """The sphere at the origin on a floor moving up at floor_speed, the lid ``gap`` above it."""
    sim = gs.Simulation(
        domain=gs.Box(lo=(-0.005, -0.005, -0.005), hi=(0.005, 0.005, 0.005)),
        contact=gs.contact.Linear(normal_stiffness=K_CONTACT, restitution=0.5, friction=0.0),
        gravity=(0.0, 0.0, 0.0),
        time_step=1e-6,
    )
    sim.add_wall(gs.Plane(point=(0, 0, -R), normal=(0, 0, 1), velocity=(0, 0, floor_speed)))
    servo = gs.geometry.Servo(
        target_force=FORCE, gain=GAIN, max_speed=max_speed, integral_gain=integral_gain
    )
    lid = sim.add_wall(gs.Plane(point=(0, 0, R + gap), normal=(0, 0, -1)), servo=servo)
    sim.add_particles(position=[(0.0, 0.0, 0.0)], radius=R, material=MAT)
    return sim, lid


def lid_loads(sim: gs.Simulation, lid: int, duration: float, every: int = 100) -> np.ndarray:
    loads = []
    while sim.time < duration - 1e-12:
        sim.run(steps=every, progress=False)
        loads.append(float(lid.force[2]))  # the sphere pushes the lid up
    return np.array(loads)


def test_proportional_servo_lags_by_speed_over_gain() -> None:
    sim, lid = sandwich(integral_gain=0.0, floor_speed=FLOOR_SPEED)
    loads = lid_loads(sim, lid, 0.03)
    expected = FORCE + FLOOR_SPEED / GAIN
    got = loads[-50:].mean()
    assert abs(got / expected - 1) <= 1e-4, (
        f"P servo load {got:.6f} N, expected F + v / gain = {expected:.6f} N"
    )
    assert lid.servo_integral == 0.0  # no integral state without an integral gain
    assert lid.velocity[2] == pytest.approx(FLOOR_SPEED, rel=1e-4)


def test_integral_servo_holds_the_target_on_a_moving_bed() -> None:
    ki = (K_CONTACT / 2) * GAIN**2 / 4  # critical damping of the linearised loop
    sim, lid = sandwich(integral_gain=ki, floor_speed=FLOOR_SPEED)
    loads = lid_loads(sim, lid, 0.04)
    got = loads[-50:].mean()
    assert abs(got / FORCE - 1) <= 1e-4, f"PI servo load {got:.6f} N, target {FORCE} N"
    integral = lid.servo_integral
    assert integral == pytest.approx(-FLOOR_SPEED / ki, rel=1e-3), (
        f"integrated error {integral:.4e} N s, expected -v / integral_gain "
        f"= {-FLOOR_SPEED / ki:.4e} N s"
    )


def test_critically_damped_pi_step_response() -> None:
    """Fixed floor, lid touching at t = 0. The linearised loop, x' = gain e + ki I with
    e = F - K x and I' = e, gives e'' + K gain e' + K ki e = 0, e(0) = F, e'(0) = -K gain F;
    at ki = K gain^2 / 4 (critical damping, w = K gain / 2): e = F (1 - w t) exp(-w t), so the
    load overshoots F by exp(-2) F at t = 2 / w and then settles without oscillating."""
    ki = (K_CONTACT / 2) * GAIN**2 / 4
    sim, lid = sandwich(integral_gain=ki, floor_speed=0.0)
    every = 10
    loads = lid_loads(sim, lid, 0.03, every=every)
    t = np.arange(1, len(loads) + 1) * every * sim.time_step
    w = (K_CONTACT / 2) * GAIN / 2
    expected = FORCE * (1 - (1 - w * t) * np.exp(-w * t))
    overshoot = loads.max() / FORCE - 1
    assert abs(overshoot - np.exp(-2)) <= 0.01, (
        f"overshoot {overshoot:.4f} F, closed form exp(-2) = {np.exp(-2):.4f} F"
    )
    worst = np.abs(loads - expected).max() / FORCE
    assert worst <= 0.05, f"load history off the closed form by up to {worst:.3f} F"
    assert abs(loads[-1] / FORCE - 1) <= 1e-5


def test_integral_does_not_wind_up_during_a_saturated_approach() -> None:
    """The lid starts 1 mm above the sphere and approaches at max_speed (gain x F is twice
    that): no error is integrated on the way, so the lid does not overshoot on contact."""
    ki = (K_CONTACT / 2) * GAIN**2 / 4
    sim, lid = sandwich(integral_gain=ki, floor_speed=0.0, gap=1e-3, max_speed=0.01)
    sim.run(steps=90_000, progress=False)  # 0.09 s of the 0.1 s approach
    assert lid.force[2] == 0.0
    assert lid.servo_integral == 0.0, "the integral wound up while saturated"
    loads = lid_loads(sim, lid, 0.2)
    assert abs(loads[-50:].mean() / FORCE - 1) <= 1e-4
    assert loads.max() <= 1.5 * FORCE, f"overshoot to {loads.max():.4f} N on contact"


def test_setting_the_servo_again_keeps_the_integral_switching_off_resets_it() -> None:
    ki = (K_CONTACT / 2) * GAIN**2 / 4
    sim, lid = sandwich(integral_gain=ki, floor_speed=FLOOR_SPEED)
    sim.run(steps=20_000, progress=False)
    before = lid.servo_integral
    assert before < 0
    lid.servo = gs.geometry.Servo(
        target_force=2 * FORCE, gain=GAIN, max_speed=0.05, integral_gain=ki
    )
    assert lid.servo_integral == before
    lid.servo = None
    assert lid.servo_integral == 0.0


def test_checkpoint_with_the_old_four_servo_values_restarts(tmp_path) -> None:
    """Checkpoints from before the PI servo hold 4 servo values (no integral gain and no
    integral): they restart as a proportional servo, exactly as a current checkpoint does."""
    import h5py

    sim, lid = sandwich(integral_gain=0.0, floor_speed=FLOOR_SPEED)
    sim.run(steps=3000, progress=False)
    new, old = tmp_path / "new.h5", tmp_path / "old.h5"
    sim.checkpoint(new)
    sim.checkpoint(old)
    key = f"rank_0/reals/walls/{lid.index}/servo"
    with h5py.File(old, "a") as f:
        values = f[key][()]
        assert len(values) == 6
        del f[key]
        f[key] = values[:4]
        f.attrs["version"] = 2  # as written before the PI servo (and the checksums)
    runs = []
    for path in (new, old):
        again, again_lid = sandwich(integral_gain=0.0, floor_speed=FLOOR_SPEED)
        with pytest.warns(UserWarning, match=r"replaced the 1 particle\(s\) this simulation"):
            again.restart(path)  # the set-up's sphere gives way to the checkpoint's
        again.run(steps=3000, progress=False)
        runs.append(np.concatenate([again_lid.force, again_lid.position]))
    assert np.array_equal(runs[0], runs[1])
    with h5py.File(old, "a") as f:
        del f[key]
        f[key] = values[:5]
    with pytest.raises(ValueError, match=r"old.h5.*'walls/\d/servo' has the wrong size"):
        sandwich(integral_gain=0.0, floor_speed=FLOOR_SPEED)[0].restart(old)
