"""The moving average of a fit's iterates (mi_voldis.optim.average) and the full phase's use of it."""
import mitsuba as mi
import numpy as np
import pytest
from conftest import TINY_FIT

from mi_voldis.optim.average import moving_average, stride, window_decay


@pytest.mark.parametrize("steps,every,beta", [(0, 1, 0.0), (0.5, 1, 0.0), (1, 1, 0.0), (4, 1, 0.75),
                                              (1000, 1, 0.999), (320, 10, 0.96875), (10, 10, 0.0)])
def test_a_window_of_steps_decays_by_the_share_of_it_between_two_iterates(steps, every, beta):
    assert window_decay(steps, every) == pytest.approx(beta)


@pytest.mark.parametrize("steps,every", [(0, 1), (31.9, 1), (64, 2), (326.25, 10), (1000, 31)])
def test_a_window_takes_about_32_iterates(steps, every):
    assert stride(steps) == every


def test_the_average_weighs_the_iterate_j_steps_back_by_one_minus_beta_times_beta_to_the_j():
    """a_n = beta^n p_0 + sum_k (1 - beta) beta^(n-k) p_k (k = 1..n), in closed form against the recursion;
    beta 0 leaves the last iterate, and the first call copies (a later change of the iterate leaves it)."""
    rng = np.random.default_rng(3)
    seq = rng.normal(size=(12, 50)).astype(np.float32)
    for beta in (0.0, 0.5, 0.9):
        a = None
        for p in seq:
            a = moving_average(a, mi.Float(p), beta)
        n = len(seq) - 1
        want = beta ** n * seq[0].astype(np.float64) + sum((1 - beta) * beta ** (n - k) * seq[k]
                                                           for k in range(1, n + 1))
        np.testing.assert_allclose(np.array(a), want, rtol=1e-5, atol=1e-6)
    p = mi.Float(seq[0])
    first = moving_average(None, p, 0.9)
    p += 1.0
    np.testing.assert_array_equal(np.array(first), seq[0])


def test_the_average_of_noise_has_the_variance_of_its_window():
    """Iterates m + e_k, e_k independent of variance s^2: once the start is forgotten, the average's
    variance is s^2 (1 - beta) / (1 + beta), 1 / (2 tau - 1) of the noise for a window of tau steps, and
    its mean m."""
    rng = np.random.default_rng(5)
    tau, m, s = 20, 0.3, 1.0
    beta = window_decay(tau)
    a = None
    for _ in range(400):  # beta^400 = 1e-9: the first iterate forgotten
        a = moving_average(a, mi.Float(m + s * rng.standard_normal(200_000).astype(np.float32)), beta)
    a = np.array(a, np.float64)
    assert abs(a.mean() - m) < 0.01
    assert a.var() == pytest.approx(s ** 2 * (1 - beta) / (1 + beta), rel=0.02)


def test_the_full_phase_ends_on_the_average_of_its_last_stage(tiny_dataset, tmp_path, monkeypatch):
    """The full field a fit keeps is the moving average of the packed values after every k-th step of its
    last stage (a window of ``average_window`` of that stage's steps; 4 iterates a window here, so k = 2),
    not its last iterate; the background phase does not average."""
    from mi_voldis.optim import average
    monkeypatch.setattr(average, "ITERATES_PER_WINDOW", 4)
    from mi_voldis.data import load_dataset
    from mi_voldis.fit import problem as problem_module
    from mi_voldis.fit.config import FitConfig
    from mi_voldis.fit.train import fit
    seen = []
    after_step = problem_module.FieldFit.after_step

    def recording(self, step):
        after_step(self, step)
        seen.append((self.phase, step, np.array(self.integrator.fields[self.roles[0]].packed, np.float64)))
    monkeypatch.setattr(problem_module.FieldFit, "after_step", recording)
    cfg = FitConfig.from_sources(None, TINY_FIT + ["sh_degree=0", "average_window=0.25"])
    _, state = fit(load_dataset(str(tiny_dataset)), str(tmp_path / "last.npz"), cfg, progress=False)
    start, steps = state.schedule[-1][0], state.steps_full
    every = stride(0.25 * (steps - start))
    assert every == 2
    last = [p for phase, step, p in seen if phase == 0 and step >= start and (step - start) % every == 0]
    assert len(last) == -(-(steps - start) // every)
    beta = window_decay(0.25 * (steps - start), every)
    want = last[0]
    for p in last[1:]:
        want = beta * want + (1 - beta) * p
    got = np.array(state.fields["full"].data, np.float64)
    np.testing.assert_allclose(got, want, rtol=1e-4, atol=1e-5)
    assert np.abs(got - last[-1]).max() > 1e-3  # not the last iterate
    assert not state.averages
