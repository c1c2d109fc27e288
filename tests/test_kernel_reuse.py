"""Kernels compile once: per-step NumPy inputs reach Dr.Jit at one alignment (mi_voldis.device), and
per-step numbers enter kernels as arrays, not as constants. A kernel's hash changes with either."""
import drjit as dr
import mitsuba as mi
import numpy as np
import pytest

from mi_voldis.data import load_dataset
from mi_voldis.device import ALIGN, aligned, from_numpy
from mi_voldis.optim.adam import Adam
from mi_voldis.raybank import RayBank


@pytest.fixture
def history():
    """Hashes of the kernels launched inside the ``with`` block of the returned context."""
    flag = dr.flag(dr.JitFlag.KernelHistory)
    dr.set_flag(dr.JitFlag.KernelHistory, True)
    dr.kernel_history()
    yield lambda: [k["hash"] for k in dr.kernel_history() if k.get("type") == dr.KernelType.JIT]
    dr.set_flag(dr.JitFlag.KernelHistory, flag)


def misaligned(values, offset):
    """``values`` as float32 in a NumPy buffer starting ``offset`` floats after an ALIGN boundary."""
    base = aligned(np.zeros(len(values) + offset), np.float32)
    out = base[offset:]
    out[...] = values
    return out


def test_from_numpy_values_and_alignment():
    rng = np.random.default_rng(0)
    p = rng.normal(size=(37, 3)).astype(np.float32)
    assert np.array_equal(np.array(from_numpy(mi.Point3f, p)).T, p)
    assert np.array_equal(np.array(from_numpy(mi.UInt32, np.arange(5))), np.arange(5))
    for offset in range(8):
        assert aligned(misaligned(p[:, 0], offset), np.float32).ctypes.data % ALIGN == 0


def test_one_kernel_whatever_the_numpy_alignment(history):
    values = np.linspace(0, 1, 1000)
    for offset in range(6):
        x = from_numpy(mi.Float, misaligned(values, offset))
        y = x * 2.0 + 1.0
        dr.eval(y)
        assert np.allclose(np.array(y), values * 2 + 1)
    assert len(set(history())) == 1


def test_ray_batches_reuse_their_kernel(tiny_dataset, history):
    ds = load_dataset(tiny_dataset)
    bank = RayBank(ds, ds.train)
    for step in range(6):
        o, d, color, mask, _ = bank.batch(np.random.default_rng(step), 333)
        dr.eval(o, d, color, mask)
    hashes = history()
    assert len(hashes) == 6 and len(set(hashes)) == 1


def test_adam_update_compiles_once(history):
    x = {"a": from_numpy(mi.Float, np.zeros(1000))}
    adam = Adam({"a": [0.1, 0.2]}, warmup=3)
    for step in range(5):
        adam.step(x, {"a": from_numpy(mi.Float, np.full(1000, 1.0 + step))}, scale=0.5 + 0.1 * step)
        dr.eval(x)
    hashes = history()
    assert len(hashes) == 5 and len(set(hashes)) == 1


@pytest.mark.parametrize("record", [True, False])
def test_training_step_builds_no_kernel_after_warmup(record):
    """The benchmark's training step (fresh rays, Adam) on a small grid: every profiled step finds
    its kernels compiled, with or without the record; the record setting is left as it was."""
    from mi_voldis.bench.throughput import step_profile
    from mi_voldis.render import march
    limit = march.RECORD_BYTES
    profile = step_profile(resolution=12, samples=16, batch=256, steps=3, warmup=2, record=record)
    assert profile["compiled"] == 0
    assert profile["primal_ms"] > 0 and profile["adjoint_ms"] > 0
    # the kernels' share of the step: their time over the step's, which holds them
    kernels = profile["primal_ms"] + profile["adjoint_ms"] + profile["other_kernels_ms"]
    assert 0 < profile["kernel_share"] <= 1 and kernels <= profile["step_ms"] * 1.05
    assert march.RECORD_BYTES == limit


@pytest.mark.parametrize("batch", ["0", "16k", "1024,,2048"])
def test_the_step_profile_refuses_a_bad_batch_in_one_line(batch, capsys):
    from voldis_cli.bench import main
    with pytest.raises(SystemExit) as stop:
        main(["--step-profile", "--batch", batch])
    assert str(stop.value) == f"error: --batch {batch!r}: expected positive whole numbers, comma-separated"
