"""The importance-weighted estimator against a model whose log-likelihood is exact.

A linear Gaussian VAE: z ~ N(0, I_d), x | z ~ N(W z + b, s^2 I_D), so
p(x) = N(x; b, W W^T + s^2 I). With the exact posterior as proposal every weight equals
log p(x) (zero variance); with a deliberately poor proposal the estimate is a lower bound in
expectation that tightens as K grows.
"""

import math

import pytest
import torch

from prg.errors import UsageError
from prg.evaluation.likelihood import iw_log_likelihood, iw_log_likelihoods
from prg.models.base import Gaussian, ImportancePath
from prg.models.likelihoods import Likelihoods

D, LATENT, STD = 200, 4, 0.1  # the trajectory likelihood's shape and std


def _model(seed=0):
    g = torch.Generator().manual_seed(seed)
    w = torch.randn(D, LATENT, generator=g) * 0.2
    b = torch.randn(D, generator=g) * 0.1
    x = (torch.randn(6, LATENT, generator=g) @ w.T + b) + STD * torch.randn(6, D, generator=g)
    return w, b, x


def _exact(w, b, x, std=STD):
    cov = w @ w.T + std**2 * torch.eye(D)
    return torch.distributions.MultivariateNormal(b, covariance_matrix=cov).log_prob(x)


def _posterior(w, b, x, std=STD):
    precision = torch.eye(LATENT) + w.T @ w / std**2
    cov = torch.linalg.inv(precision)
    mean = (x - b) @ w @ cov.T / std**2
    return mean, torch.log(torch.diagonal(cov)).expand_as(mean), cov


def _path(mu, logvar, w, b):
    return ImportancePath(Gaussian(mu, logvar), lambda z: z @ w.T + b, "traj", LATENT)


def test_matches_the_closed_form_with_a_good_proposal():
    """Tolerance 0.05 nats per sample at K = 2000 (measured error 0.005)."""
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    # the diagonal of the exact posterior: near-exact, small variance
    est = iw_log_likelihood(
        _path(mean, logvar, w, b),
        x,
        Likelihoods(STD),
        k=2000,
        generator=torch.Generator().manual_seed(1),
    )
    torch.testing.assert_close(est, _exact(w, b, x), atol=0.05, rtol=0)


def test_tightens_as_k_grows_with_a_poor_proposal():
    w, b, x = _model(1)
    mean, logvar, _ = _posterior(w, b, x)
    poor = _path(mean + 0.5 * torch.exp(0.5 * logvar), logvar + 1.0, w, b)  # off and too wide
    exact = _exact(w, b, x)
    gaps = []
    for k in (1, 10, 100, 1000, 5000):
        est = iw_log_likelihood(
            poor, x, Likelihoods(STD), k=k, generator=torch.Generator().manual_seed(k)
        )
        gaps.append((exact - est).mean().item())
    # measured: 3.01, -0.05, 0.04, -0.003, 0.0002 nats (seeded); K = 1 is the loose ELBO-like
    # bound, K = 1000 and 5000 are within the stated tolerances of the exact value
    assert gaps[0] > 1.0
    assert abs(gaps[3]) < 0.05
    assert abs(gaps[4]) < 0.02
    assert abs(gaps[4]) < 0.05 * gaps[0]


def test_chunking_does_not_change_the_estimate():
    """Drawn in chunks of 50 or all at once from the same seeded stream: the same samples, so
    the running log-sum-exp must give the same estimate (bounded memory costs nothing). (torch's
    CPU sampler keeps one stream only for draws of a multiple of 16 values; chunks of 7 draw
    other samples and agree within Monte Carlo error.)"""
    w, b, x = _model(2)
    mean, logvar, _ = _posterior(w, b, x)
    path = _path(mean + 0.5 * torch.exp(0.5 * logvar), logvar, w, b)

    def estimate(chunk):
        g = torch.Generator().manual_seed(3)
        return iw_log_likelihood(path, x, Likelihoods(STD), k=300, chunk=chunk, generator=g)

    whole = estimate(300)
    torch.testing.assert_close(estimate(50), whole, atol=1e-4, rtol=0)
    assert (estimate(7) - whole).abs().max() < 0.5


@pytest.mark.parametrize("k", [0, -3, 2.5])
def test_k_below_one_is_refused(k):
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    with pytest.raises(UsageError, match="K must be an integer >= 1"):
        iw_log_likelihood(_path(mean, logvar, w, b), x, Likelihoods(STD), k=k)


def test_single_sample_is_the_elbo_estimate():
    w, b, x = _model(3)
    mean, logvar, _ = _posterior(w, b, x)
    g = torch.Generator().manual_seed(5)
    est = iw_log_likelihood(_path(mean, logvar, w, b), x, Likelihoods(STD), k=1, generator=g)
    assert torch.isfinite(est).all()
    assert math.isfinite(float(est.mean()))


def test_several_likelihoods_in_one_pass_equal_separate_passes():
    """One pass under stds 0.1, 1.0 and 0.3 (shared latent samples and decoder outputs) gives,
    row by row, what a separate pass with the same seed gives."""
    w, b, x = _model(4)
    mean, logvar, _ = _posterior(w, b, x)
    path = _path(mean + 0.3 * torch.exp(0.5 * logvar), logvar + 0.5, w, b)
    stds = (STD, 1.0, 0.3)
    together = iw_log_likelihoods(
        path,
        x,
        [Likelihoods(s) for s in stds],
        k=400,
        chunk=80,
        generator=torch.Generator().manual_seed(7),
    )
    assert together.shape == (3, len(x))
    for row, std in zip(together, stds):
        alone = iw_log_likelihood(
            path, x, Likelihoods(std), k=400, chunk=80, generator=torch.Generator().manual_seed(7)
        )
        torch.testing.assert_close(row, alone, atol=1e-4, rtol=0)
    assert (together[0] - together[1]).abs().min() > 50  # different conventions, not one copied


def test_unit_variance_row_matches_its_closed_form():
    """Scored under std 1 (Table I's main convention), with the std-1 posterior as proposal, the
    estimate is the exact log N(x; b, W W^T + I), while the std-0.1 row of the same pass is a
    different number (its own density)."""
    w, b, x = _model(5)
    mean, logvar, _ = _posterior(w, b, x, std=1.0)
    est = iw_log_likelihoods(
        _path(mean, logvar, w, b),
        x,
        [Likelihoods(1.0), Likelihoods(STD)],
        k=2000,
        generator=torch.Generator().manual_seed(2),
    )
    torch.testing.assert_close(est[0], _exact(w, b, x, std=1.0), atol=0.05, rtol=0)
    assert (est[1] - _exact(w, b, x, std=1.0)).abs().min() > 50


def test_an_empty_list_of_likelihoods_is_refused():
    w, b, x = _model()
    mean, logvar, _ = _posterior(w, b, x)
    with pytest.raises(UsageError, match="no likelihood"):
        iw_log_likelihoods(_path(mean, logvar, w, b), x, [], k=3)
