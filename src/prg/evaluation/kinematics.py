"""How a pen moves: the measures that tell a hand's motion from a machine's.

Every function takes a pen path sampled uniformly in time, ``xy`` (n, 2) at ``dt`` seconds,
and returns plain numbers:

- :func:`power_law`: the speed-curvature power law ``v = K kappa^(-beta)`` fitted by least
  squares of ``log v`` on ``log kappa`` (Savitzky-Golay derivatives over
  :data:`prg.pipeline.timing.WINDOW_S`, samples above 5 % of the peak speed); ``beta`` with the fit's R^2. Hands give beta near 1/3 for elliptic and cursive
  movements (Lacquaniti, Terzuolo & Viviani 1983). The estimator is biased by noise: white
  noise alone gives about 0.25 (Maoz et al. 2005), so it is always reported beside that control
  (:func:`controls`) and beside a constant-speed path (beta about 0);
- :func:`speed_cv`: the speed's coefficient of variation over the same samples;
- :func:`peaks_per_s`: speed maxima per second (prominence 5 % of the peak speed);
- :func:`sparc`: the spectral arc length of the speed profile (Balasubramanian, Melendez-
  Calderon & Burdet 2012; cut-off 10 Hz and 5 % amplitude as in Balasubramanian et al. 2015):
  closer to 0 is smoother;
- :func:`lognormal_snr`: the SNR of a sigma-lognormal model (:mod:`prg.data.sigma_lognormal`)
  fitted to the path at its times, components up to one per 0.1 s: how well the motion is
  explained as a sum of rapid human strokes (Plamondon's kinematic theory).

:func:`kinematics` gathers them; :func:`controls` makes the white-noise and constant-speed
paths the report shows beside every row.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.signal import find_peaks

from prg.pipeline.timing import WINDOW_S, speed_and_curvature

MIN_SPEED = 0.05  # share of the peak speed below which samples are left out (pen at rest)


def speeds(xy: np.ndarray, dt: float, window_s: float = WINDOW_S) -> np.ndarray:
    """Pen speed per sample (:func:`prg.pipeline.timing.speed_and_curvature`)."""
    return speed_and_curvature(xy, dt, window_s)[0]


def power_law(xy: np.ndarray, dt: float, window_s: float = WINDOW_S) -> dict[str, float]:
    """The speed-curvature power law's exponent ``beta``, ``log_k`` and the fit's ``r2``.

    Examples
    --------
    >>> t = np.arange(0, 4, 0.01)
    >>> a, b = 2.0, 1.0                       # an ellipse at constant angular speed
    >>> xy = np.column_stack([a * np.cos(2 * np.pi * t), b * np.sin(2 * np.pi * t)])
    >>> round(power_law(xy, 0.01)["beta"], 2)  # exactly 1/3 for harmonic motion
    0.33
    """
    v, kappa = speed_and_curvature(xy, dt, window_s)
    keep = (v > MIN_SPEED * v.max()) & (kappa > 0)
    if keep.sum() < 3:
        return {"beta": float("nan"), "log_k": float("nan"), "r2": float("nan")}
    x, y = np.log(kappa[keep]), np.log(v[keep])
    slope, intercept = np.polyfit(x, y, 1)
    residual = y - (slope * x + intercept)
    r2 = 1.0 - residual.var() / y.var() if y.var() > 0 else float("nan")
    return {"beta": float(-slope), "log_k": float(intercept), "r2": float(r2)}


def speed_cv(xy: np.ndarray, dt: float) -> float:
    """Standard deviation over mean of the speed, samples above 5 % of its peak."""
    v = speeds(xy, dt)
    v = v[v > MIN_SPEED * v.max()]
    return float(v.std() / v.mean()) if len(v) else float("nan")


def peaks_per_s(xy: np.ndarray, dt: float) -> float:
    """Speed maxima per second of motion (prominence at least 5 % of the peak speed)."""
    v = speeds(xy, dt)
    peaks, _ = find_peaks(v, prominence=MIN_SPEED * v.max())
    return len(peaks) / (dt * (len(v) - 1))


def sparc(xy: np.ndarray, dt: float, cutoff_hz: float = 10.0, threshold: float = 0.05) -> float:
    """Spectral arc length of the speed profile (negative; closer to 0 is smoother).

    Examples
    --------
    >>> t = np.arange(0, 1, 0.01)
    >>> bell = np.column_stack([t**3 * (10 - 15 * t + 6 * t**2), 0 * t])  # minimum jerk
    >>> -2 < sparc(bell, 0.01) < -1.3
    True
    """
    v = speeds(xy, dt)
    n = int(2 ** math.ceil(math.log2(len(v)) + 4))  # zero padding for a fine spectrum
    spectrum = np.abs(np.fft.rfft(v, n))
    freq = np.fft.rfftfreq(n, dt)
    if spectrum.max() <= 0:
        return float("nan")
    mag = spectrum / spectrum.max()
    inside = freq <= cutoff_hz
    freq, mag = freq[inside], mag[inside]
    above = np.flatnonzero(mag >= threshold)
    last = above[-1] if len(above) else len(mag) - 1
    freq, mag = freq[: last + 1], mag[: last + 1]
    d_freq = np.diff(freq) / (freq[-1] - freq[0]) if freq[-1] > freq[0] else np.diff(freq)
    return float(-np.sum(np.sqrt(d_freq**2 + np.diff(mag) ** 2)))


def lognormal_snr(xy: np.ndarray, dt: float, components_per_s: float = 10.0) -> float:
    """SNR (dB) of a sigma-lognormal fit to the path at its sample times."""
    from prg.data.sigma_lognormal import fit

    t = np.arange(len(xy)) * dt
    duration = float(t[-1]) if len(t) else 0.0
    result = fit(
        np.asarray(xy, dtype=np.float64),
        t,
        max_components=max(3, math.ceil(components_per_s * duration)),
    )
    return float(result.snr_db)


def kinematics(xy: np.ndarray, dt: float, lognormal: bool = True) -> dict[str, float]:
    """Every measure of one path: ``beta``, ``r2``, ``speed_cv``, ``peaks_per_s``, ``sparc``
    and (``lognormal``) ``lognormal_snr_db``."""
    law = power_law(xy, dt)
    out = {
        "beta": law["beta"],
        "r2": law["r2"],
        "speed_cv": speed_cv(xy, dt),
        "peaks_per_s": peaks_per_s(xy, dt),
        "sparc": sparc(xy, dt),
    }
    if lognormal:
        out["lognormal_snr_db"] = lognormal_snr(xy, dt)
    return out


def controls(xy: np.ndarray, dt: float, seed: int = 0) -> dict[str, np.ndarray]:
    """The two paths every report shows beside its rows, each as long as ``xy``:
    ``white noise`` (independent Gaussian positions, the estimator's bias: beta about 0.25) and
    ``constant speed`` (``xy``'s own path at its mean speed: beta about 0)."""
    rng = np.random.default_rng(seed)
    noise = rng.normal(size=np.asarray(xy).shape)
    steps = np.linalg.norm(np.diff(xy, axis=0), axis=1)
    arc = np.concatenate([[0.0], np.cumsum(steps)])
    s = np.linspace(0.0, arc[-1], len(xy))
    constant = np.column_stack([np.interp(s, arc, xy[:, 0]), np.interp(s, arc, xy[:, 1])])
    return {"white noise": noise, "constant speed": constant}


#: The measures of each row of the kinematics report.
MEASURES = ("beta", "r2", "speed_cv", "peaks_per_s", "sparc", "lognormal_snr_db")

#: Targets on the executed pen tip with the human timing (medians over the words).
TARGETS = {"beta": (0.2, 0.4), "speed_cv": (0.25, None), "lognormal_snr_db": (20.0, None)}


def executed_tip(result, dt: float = 0.01) -> np.ndarray:
    """The simulated pen tip along a word's body (its first commanded stroke), every ``dt``
    seconds, from a :class:`prg.sim.SimResult`."""
    body = result.step_stroke == 0
    t, xy = result.t[body], result.tip_paper[body, :2]
    grid = np.arange(t[0], t[-1], dt)
    return np.column_stack([np.interp(grid, t, xy[:, 0]), np.interp(grid, t, xy[:, 1])])


def kinematics_rows(
    model, hands, words, robot: str = "panda", lasa: bool = True, progress=None
) -> dict[str, list[dict[str, float]]]:
    """Per group, the measures of every path: each word written (seed ``i``) with the human
    timing and the paper's constant speed, as planned (the DMP's rollout) and as the simulated
    ``robot`` executes it; the LASA demonstrations (``lasa``) and the two controls."""
    from prg.pipeline.compose import GenerateSettings
    from prg.pipeline.timing import timed_body
    from prg.sim import simulate_word
    from prg.writer import Writer

    groups: dict[str, list[dict[str, float]]] = {}
    for timing in ("human", "constant"):
        for i, text in enumerate(words):
            settings = GenerateSettings(seed=i, timing=timing)
            result = Writer(model, settings, hands=hands).write(text=text)
            samples, duration = timed_body(result.word.body, settings)
            dt = duration / (len(samples) - 1)
            groups.setdefault(f"{timing}: planned", []).append(kinematics(result.rollout, dt))
            sim = simulate_word(result.word, robot, render=False)
            groups.setdefault(f"{timing}: executed", []).append(kinematics(executed_tip(sim), 0.01))
            if progress:
                progress(f"{timing} {text!r}")
    if lasa:
        from prg.data.lasa import load_demos

        demos = load_demos()
        groups["LASA (human)"] = [
            kinematics(d.positions, float(np.diff(d.times).mean())) for d in demos
        ]
        step = float(np.diff(demos[0].times).mean())
        for name, path in controls(demos[0].positions, step).items():
            groups[f"control: {name}"] = [kinematics(path, step)]
    return groups


def medians(groups: dict[str, list[dict[str, float]]]) -> list[dict]:
    """One row per group: ``group``, ``paths`` and the median of each measure."""
    return [
        {
            "group": name,
            "paths": len(rows),
            **{m: float(np.median([r[m] for r in rows])) for m in MEASURES},
        }
        for name, rows in groups.items()
    ]
