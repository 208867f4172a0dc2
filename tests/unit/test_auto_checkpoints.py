"""Periodic checkpoints (sim.checkpoint_every, grainscale.io.Checkpoints; issue 26 point 5):
the newest k files are kept, writing them does not change the run, and the newest restarts
bit-identically against the run that went on."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from test_checkpoint import LAWS, build, populated, snapshot

import grainscale as gs


def test_newest_kept_and_the_last_restarts_bit_identically(tmp_path: Path) -> None:
    law = LAWS[0]
    ran = populated(law)
    ck = ran.checkpoint_every(tmp_path / "ck", every_steps=200, keep=2)
    assert isinstance(ck, gs.io.Checkpoints) and ran.outputs == [ck]
    ran.run(steps=700)
    ran.run(steps=300)
    names = [f"checkpoint_{s:010d}.h5" for s in (200, 400, 600, 800, 1000)]
    assert [p.name for p in ck.files] == names  # nothing at the attachment step 0
    assert [p.name for p in ck.kept()] == names[-2:]
    assert sorted(p.name for p in (tmp_path / "ck").iterdir()) == names[-2:]  # no temporaries
    assert [p.name for p in ck.removed] == names[:3]

    straight = populated(law)  # the same run without checkpoints
    straight.run(steps=1000)
    for key, value in snapshot(straight).items():
        assert np.array_equal(snapshot(ran)[key], value), f"{key}: checkpoints changed the run"

    latest = gs.io.latest_checkpoint(tmp_path / "ck")
    assert latest == tmp_path / "ck" / names[-1]
    again = build(law)
    again.restart(latest)
    assert again.step == 1000
    ran.run(steps=5000)
    again.run(steps=5000)
    assert again.num_contacts() > 30
    expected = snapshot(ran)
    for key, value in snapshot(again).items():
        assert np.array_equal(value, expected[key]), f"{key} differs after the restart"


def test_a_restarted_run_continues_the_files(tmp_path: Path) -> None:
    pattern = tmp_path / "run_{step:06d}.h5"
    first = populated(LAWS[1])
    first.checkpoint_every(pattern, every=2e-3, keep=3)  # time_step 1e-5 s: every 200 steps
    first.run(steps=1000)
    assert [p.name for p in gs.io.Checkpoints(pattern, every=1.0).kept()] == [
        "run_000600.h5",
        "run_000800.h5",
        "run_001000.h5",
    ]
    # a restart from step 800 (the 1000 file is of the abandoned history): nothing written at
    # 800, the older files counted in `keep`, the later one left alone until it is rewritten
    again = build(LAWS[1])
    again.restart(tmp_path / "run_000800.h5")
    ck = again.checkpoint_every(pattern, every=2e-3, keep=2)
    (tmp_path / "run_009000.h5").write_bytes(b"a later history")
    again.run(steps=200)
    assert [p.name for p in ck.files] == ["run_001000.h5"]
    assert [p.name for p in ck.kept()] == ["run_000800.h5", "run_001000.h5", "run_009000.h5"]
    assert gs.io.latest_checkpoint(pattern) == tmp_path / "run_009000.h5"


def test_log_notes_each_checkpoint(tmp_path: Path) -> None:
    sim = populated(LAWS[0])
    sim.log(tmp_path / "run.log")
    sim.checkpoint_every(tmp_path, every_steps=50, keep=None)
    sim.run(steps=100)
    text = (tmp_path / "run.log").read_text()
    assert f"# checkpoint {tmp_path / 'checkpoint_0000000050.h5'} (step 50," in text
    assert len(list(tmp_path.glob("checkpoint_*.h5"))) == 2


@pytest.mark.parametrize(
    ("path", "kwargs", "message"),
    [
        ("ck", {}, "Checkpoints needs exactly one of every"),
        ("ck", {"every_steps": 10, "keep": 0}, "Checkpoints.keep must be a positive integer"),
        ("ck", {"every_steps": 10, "keep": 1.5}, "Checkpoints.keep must be a positive integer"),
        ("ck_{stp}.h5", {"every_steps": 10}, r"exactly one \{step\} field"),
        ("ck_{step}_{step}.h5", {"every_steps": 10}, r"exactly one \{step\} field"),
        ("{step}/ck.h5", {"every_steps": 10}, r"exactly one \{step\} field, in its file name"),
        ("ck_{step:q}.h5", {"every_steps": 10}, "bad pattern"),
    ],
)
def test_validation(tmp_path: Path, path: str, kwargs: dict, message: str) -> None:
    with pytest.raises(ValueError, match=message):
        gs.io.Checkpoints(tmp_path / path, **kwargs)


def test_checkpoint_every_validates_before_registering(tmp_path: Path) -> None:
    sim = populated(LAWS[0])
    with pytest.raises(ValueError, match="Checkpoints.every must be a positive finite time"):
        sim.checkpoint_every(tmp_path, every=-1.0)
    assert sim.outputs == []
