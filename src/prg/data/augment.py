"""Class-balanced data augmentation of character trajectories with the sigma-lognormal model.

Every original trajectory is timed with the two-thirds power law and fitted with a
sigma-lognormal model (:mod:`prg.data.sigma_lognormal`); new samples are drawn by perturbing the
fitted components (:func:`~prg.data.sigma_lognormal.perturb`), re-evaluating the stroke at the
original's time stamps (refined 4x, so the polyline follows the curve), resampling it to ``n``
equidistant points and normalising it
(:mod:`prg.data.preprocess`).

Rules
-----
* **Balance.** Each class gets exactly ``per_class`` new samples, drawn round-robin over the
  class's *parents* in index order: the ``j``-th sample of a class comes from parent
  ``j mod len(parents)``. Originals are not part of the output (the caller concatenates).
* **Failed fits.** A fit that misses the SNR target is not a parent when its class has at least
  one successful fit. A class without any successful fit gets its originals copied unchanged
  (round-robin, still ``per_class`` samples); ``stats["classes_copied"]`` and
  ``stats["n_copied"]`` count this.
* **Degenerate draws.** A perturbed stroke that is not finite or has (near) zero length or extent
  is redrawn, up to ``max_redraws`` times; after that the parent original is copied
  (``stats["n_copied"]``; ``stats["n_redraws"]`` counts every redraw).
* **Determinism.** The ``r``-th sample drawn from original ``i`` uses the random stream
  ``SeedSequence(seed, spawn_key=(i, r))``; fits are deterministic. The output is therefore the
  same bit for bit for any ``workers``.
* **Parallelism.** With ``workers > 1`` fits and draws run in a
  :class:`~concurrent.futures.ProcessPoolExecutor` (``forkserver`` start method on Linux, so
  threads of the parent process, e.g. from torch, cannot deadlock the children; ``spawn``
  elsewhere), in chunks, with a tqdm progress bar. A failing chunk cancels the rest and re-raises
  instead of hanging.
"""

from __future__ import annotations

import multiprocessing
import os
import signal
import threading
import time
from collections.abc import Callable, Sequence
from concurrent.futures import Future, ProcessPoolExecutor, as_completed
from concurrent.futures.process import BrokenProcessPool
from contextlib import suppress
from dataclasses import dataclass, field
from multiprocessing.connection import Connection

import numpy as np
from tqdm.auto import tqdm

from prg.data import sigma_lognormal as sl
from prg.data.preprocess import normalise, resample_arclength
from prg.errors import PRGError, UsageError
from prg.fields import check_fields, checked, integer, number

_CHUNK = 32  # trajectories per fit task
_DRAW_CHUNK = 512  # samples per draw task
_DENSITY = 4  # time samples per original sample when evaluating a perturbed stroke


@dataclass(frozen=True)
class AugmentSettings:
    """Settings of :func:`augment` (``data.augment`` in the Hydra config).

    Attributes
    ----------
    enabled : bool
        Whether the dataset build augments at all (its switch; :func:`augment` ignores it).
    per_class : int
        New samples per class (originals not included), ``>= 0``.
    snr_target_db : float
        Point SNR a fit must reach (:func:`prg.data.sigma_lognormal.fit`).
    max_components : int
        Most lognormal components of a fit, ``>= 1``.
    amplitude, rotation_deg, sweep : float
        Perturbation ranges (:func:`prg.data.sigma_lognormal.perturb`), ``>= 0``; :func:`augment`
        also needs ``amplitude < 1``.
    """

    enabled: bool = True
    per_class: int = checked(1000, integer, minimum=0)
    snr_target_db: float = checked(20.0, number)
    max_components: int = checked(15, integer)
    amplitude: float = checked(0.1, number, minimum=0.0)
    rotation_deg: float = checked(5.0, number, minimum=0.0)
    sweep: float = checked(0.05, number, minimum=0.0)

    def __post_init__(self) -> None:
        check_fields(self)


@dataclass
class AugmentResult:
    """Output of :func:`augment`.

    Attributes
    ----------
    trajectories : ndarray, shape (M, n, 2), float32
        New samples only, normalised, ``n`` equidistant points each; grouped by class in sorted
        label order.
    labels : ndarray, shape (M,)
        Class of each sample (dtype of the input labels).
    parent : ndarray, shape (M,), int64
        Index into the input of the original each sample was drawn (or copied) from.
    stats : dict
        JSON-serialisable numbers: fit quality (see :func:`fit_quality_summary`), ``fit_seconds``
        (wall clock of the fitting phase), ``fit_seconds_mean`` (per trajectory, CPU of one
        worker), ``n_generated``, ``n_copied``, ``n_redraws``, ``classes_copied``, ``per_class``,
        ``n_classes``.
    """

    trajectories: np.ndarray
    labels: np.ndarray
    parent: np.ndarray
    stats: dict = field(default_factory=dict)


@dataclass(frozen=True)
class _Fitted:
    """Per-original fit as passed between processes."""

    result: sl.FitResult
    t: np.ndarray
    seconds: float


def fit_quality_summary(results: Sequence[sl.FitResult]) -> dict:
    """Aggregate fit quality.

    Parameters
    ----------
    results : sequence of FitResult

    Returns
    -------
    dict
        ``n_fits``, ``n_fitted`` (successful), ``n_failed``, ``failure_rate``, ``snr_db_mean``,
        ``snr_db_median``, ``snr_db_p10`` (over all fits), ``components_mean``; plain floats and
        ints (NaN-free: 0.0 when there are no fits).
    """
    n = len(results)
    snr = np.array([r.snr_db for r in results], dtype=np.float64)
    ok = np.array([r.success for r in results], dtype=bool)
    comps = np.array([r.n_components for r in results], dtype=np.float64)

    def stat(fn: Callable[[np.ndarray], float], values: np.ndarray) -> float:
        return float(fn(values)) if values.size else 0.0

    n_ok = int(ok.sum())
    return {
        "n_fits": n,
        "n_fitted": n_ok,
        "n_failed": n - n_ok,
        "failure_rate": float((n - n_ok) / n) if n else 0.0,
        "snr_db_mean": stat(np.mean, snr),
        "snr_db_median": stat(np.median, snr),
        "snr_db_p10": stat(lambda v: np.percentile(v, 10), snr),
        "components_mean": stat(np.mean, comps),
    }


def fit_trajectory(
    points: np.ndarray, snr_target_db: float = 20.0, max_components: int = 15
) -> tuple[sl.FitResult, np.ndarray]:
    """Time one preprocessed trajectory with the power law and fit it.

    Parameters
    ----------
    points : ndarray, shape (n, 2)
    snr_target_db, max_components : see :func:`prg.data.sigma_lognormal.fit`

    Returns
    -------
    (FitResult, ndarray of shape (n,))
        The fit and the time stamps it refers to.
    """
    t = sl.power_law_timestamps(points)
    return sl.fit(points, t, snr_target_db=snr_target_db, max_components=max_components), t


def _fit_chunk(chunk: np.ndarray, snr_target_db: float, max_components: int) -> list[_Fitted]:
    out = []
    for points in chunk:
        start = time.perf_counter()
        result, t = fit_trajectory(points, snr_target_db, max_components)
        out.append(_Fitted(result, t, time.perf_counter() - start))
    return out


def _valid_stroke(points: np.ndarray) -> bool:
    if not np.all(np.isfinite(points)):
        return False
    length = np.linalg.norm(np.diff(points, axis=0), axis=1).sum()
    extent = np.abs(points - points.mean(axis=0)).max()
    return bool(length > 1e-6 and extent > 1e-6)


def _draw(
    fitted: _Fitted,
    original: np.ndarray,
    rng: np.random.Generator,
    ranges: tuple[float, float, float],
    max_redraws: int,
) -> tuple[np.ndarray, int, bool]:
    """One perturbed sample: (points (n, 2), redraws used, copied the original instead)."""
    n = original.shape[0]
    res = fitted.result
    # Evaluate on a 4x denser time grid so that the polyline resampling follows the curve.
    dense_t = np.interp(np.linspace(0, n - 1, _DENSITY * (n - 1) + 1), np.arange(n), fitted.t)
    for attempt in range(max_redraws + 1):
        params = sl.perturb(res.params, rng, *ranges)
        with np.errstate(all="ignore"):
            stroke = sl.trajectory(params, dense_t, res.start)
        if not _valid_stroke(stroke):
            continue
        try:
            sample = normalise(resample_arclength(stroke, n))
        except UsageError:
            continue
        if np.all(np.isfinite(sample)):
            return sample, attempt, False
    return original.copy(), max_redraws, True


def _draw_chunk(
    jobs: list[tuple[int, int]],
    fits: dict[int, _Fitted],
    originals: dict[int, np.ndarray],
    seed: int,
    ranges: tuple[float, float, float],
    max_redraws: int,
) -> tuple[np.ndarray, int, int]:
    """Draw samples ``(parent, r)``; returns (samples (len, n, 2), redraws, copies)."""
    n = next(iter(originals.values())).shape[0]
    out = np.empty((len(jobs), n, 2), dtype=np.float64)
    redraws = copies = 0
    for row, (parent, r) in enumerate(jobs):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(parent, r)))
        out[row], used, copied = _draw(fits[parent], originals[parent], rng, ranges, max_redraws)
        redraws += used
        copies += int(copied)
    return out, redraws, copies


def _worker_init(parent_alive=None) -> None:
    """Single-threaded BLAS in each worker: the small dense solves of the fit gain nothing from
    threads, and ``workers`` processes with a thread per core each oversubscribe the CPU (about
    1.4x slower measured on 2 cores). Uses threadpoolctl when it is installed.

    Ctrl-C reaches the whole process group: a worker ignores it, the main process stops the pool.

    ``parent_alive``: the read end of a pipe whose only write end the main process holds
    (:func:`_parent_watch`). A thread waits on it and ends the worker the moment the main
    process is gone, however it died (``SIGKILL`` included, when nothing stops the pool): a
    forkserver worker is not the main process's child, and without this it would hang for ever
    on the result pipe, keeping the fork server and the resource tracker alive with it.
    """
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    if parent_alive is not None:
        threading.Thread(
            target=_exit_when_closed, args=(parent_alive,), name="parent-watch", daemon=True
        ).start()
    try:
        from threadpoolctl import threadpool_limits
    except ImportError:  # optional: without it the workers keep the default thread count
        return
    threadpool_limits(limits=1, user_api="blas")


def _exit_when_closed(reader: Connection) -> None:
    """Block until the pipe's write end is closed (nothing is ever sent), then end this process
    at once: no cleanup that could wait on the dead parent."""
    with suppress(EOFError, OSError):
        reader.recv_bytes()
    os._exit(1)


def _parent_watch(context: multiprocessing.context.BaseContext) -> tuple[Connection, Connection]:
    """A one-way pipe for :func:`_worker_init`: (read end for the workers, write end kept by this
    process, closed only by its death or after the pool has ended)."""
    return context.Pipe(duplex=False)


def _stop_pool(pool: ProcessPoolExecutor) -> None:
    """Terminate the pool's workers and wait for them to end (``shutdown`` alone would wait for
    the running tasks to finish; Python 3.14 names this ``terminate_workers``)."""
    terminate = getattr(pool, "terminate_workers", None)
    if terminate is not None:
        terminate()
        return
    for process in list((pool._processes or {}).values()):  # no public way before 3.14
        process.terminate()
    # A task can be half-written into the pipe that only the dead workers read; the queue's
    # feeder thread then blocks for ever and shutdown waits on it (CPython gh-94777, fixed in
    # 3.12). Closing our copy of the read end makes that write fail, so the feeder ends.
    call_queue = getattr(pool, "_call_queue", None)
    if call_queue is not None:
        call_queue._reader.close()
    pool.shutdown(wait=True, cancel_futures=True)


def _pool_context() -> multiprocessing.context.BaseContext:
    methods = multiprocessing.get_all_start_methods()
    return multiprocessing.get_context("forkserver" if "forkserver" in methods else "spawn")


def _run_tasks(
    fn: Callable,
    tasks: list[tuple],
    pool: ProcessPoolExecutor | None,
    bar: tqdm,
    sizes: list[int],
) -> list:
    """Run ``fn(*task)`` for every task, inline or in the pool; results in task order."""
    results: list = [None] * len(tasks)
    if pool is None:
        for i, task in enumerate(tasks):
            results[i] = fn(*task)
            bar.update(sizes[i])
        return results
    futures: dict[Future, int] = {pool.submit(fn, *task): i for i, task in enumerate(tasks)}
    try:
        for fut in as_completed(futures):
            i = futures[fut]
            results[i] = fut.result()
            bar.update(sizes[i])
    except BrokenProcessPool:
        for fut in futures:
            fut.cancel()
        raise PRGError(
            "an augmentation worker process died (out of memory, or killed); "
            "run again, or with workers=1"
        ) from None
    except BaseException:
        for fut in futures:
            fut.cancel()
        raise
    return results


def augment(
    trajectories: np.ndarray,
    labels: np.ndarray,
    settings: AugmentSettings | None = None,
    *,
    seed: int = 0,
    workers: int = 2,
    progress: bool = True,
    max_redraws: int = 10,
) -> AugmentResult:
    """Generate ``settings.per_class`` sigma-lognormal variations for every class.

    Parameters
    ----------
    trajectories : ndarray, shape (N, n, 2)
        Preprocessed originals (equidistant, normalised).
    labels : ndarray, shape (N,)
        Class of each original.
    settings : AugmentSettings, optional
        Samples per class, fit settings and perturbation ranges; default ``AugmentSettings()``.
    seed : int
        Seed of all random draws (see the module docstring for how streams are derived).
    workers : int
        Processes; ``1`` runs everything inline.
    progress : bool
        Show tqdm progress bars.
    max_redraws : int
        Redraws of a degenerate sample before the original is copied.

    Returns
    -------
    AugmentResult

    Raises
    ------
    UsageError
        On malformed inputs or settings.
    """
    settings = settings or AugmentSettings()
    per_class = settings.per_class
    amplitude, rotation_deg, sweep = settings.amplitude, settings.rotation_deg, settings.sweep
    trajs = np.asarray(trajectories, dtype=np.float64)
    labels = np.asarray(labels)
    if trajs.ndim != 3 or trajs.shape[2] != 2 or trajs.shape[1] < 3:
        raise UsageError(f"trajectories must have shape (N, n>=3, 2), got {trajs.shape}")
    if labels.shape != (trajs.shape[0],):
        raise UsageError(f"labels must have shape ({trajs.shape[0]},), got {labels.shape}")
    if not np.all(np.isfinite(trajs)):
        raise UsageError("trajectories contain NaN or infinite values")
    if per_class < 0 or workers < 1 or max_redraws < 0:
        raise UsageError(
            f"need per_class >= 0, workers >= 1, max_redraws >= 0; got per_class={per_class}, "
            f"workers={workers}, max_redraws={max_redraws}"
        )
    if min(amplitude, rotation_deg, sweep) < 0 or amplitude >= 1:
        raise UsageError(
            f"perturbation ranges must be >= 0 (amplitude < 1), got amplitude={amplitude}, "
            f"rotation_deg={rotation_deg}, sweep={sweep}"
        )
    n_in, n_pts = trajs.shape[0], trajs.shape[1]
    classes = np.unique(labels)
    ranges = (float(amplitude), float(rotation_deg), float(sweep))

    pool, watch = None, None
    if workers > 1 and n_in > 0:
        context = _pool_context()
        watch = _parent_watch(context)
        pool = ProcessPoolExecutor(
            max_workers=workers,
            mp_context=context,
            initializer=_worker_init,
            initargs=(watch[0],),
        )
    try:
        start = time.perf_counter()
        starts = list(range(0, n_in, _CHUNK))
        fit_settings = (settings.snr_target_db, settings.max_components)
        tasks = [(trajs[i : i + _CHUNK], *fit_settings) for i in starts]
        sizes = [min(_CHUNK, n_in - i) for i in starts]
        with tqdm(total=n_in, desc="fit sigma-lognormal", disable=not progress) as bar:
            chunks = _run_tasks(_fit_chunk, tasks, pool, bar, sizes)
        fits: list[_Fitted] = [f for chunk in chunks for f in chunk]
        fit_seconds = time.perf_counter() - start

        # Plan: (parent, r) per output sample; copies for classes without a successful fit.
        plan_parent: list[int] = []
        plan_draw: list[bool] = []
        plan_r: list[int] = []
        classes_copied = 0
        for c in classes:
            members = np.flatnonzero(labels == c)
            good = [int(i) for i in members if fits[i].result.success]
            parents = good if good else [int(i) for i in members]
            classes_copied += int(not good)
            for j in range(per_class):
                plan_parent.append(parents[j % len(parents)])
                plan_r.append(j // len(parents))
                plan_draw.append(bool(good))

        m = len(plan_parent)
        out = np.empty((m, n_pts, 2), dtype=np.float32)
        draw_rows = [i for i in range(m) if plan_draw[i]]
        for i in range(m):
            if not plan_draw[i]:
                out[i] = trajs[plan_parent[i]]
        tasks, sizes = [], []
        for lo in range(0, len(draw_rows), _DRAW_CHUNK):
            rows = draw_rows[lo : lo + _DRAW_CHUNK]
            jobs = [(plan_parent[i], plan_r[i]) for i in rows]
            used = sorted({p for p, _ in jobs})
            tasks.append(
                (
                    jobs,
                    {p: fits[p] for p in used},
                    {p: trajs[p] for p in used},
                    seed,
                    ranges,
                    max_redraws,
                )
            )
            sizes.append(len(rows))
        with tqdm(total=len(draw_rows), desc="draw samples", disable=not progress) as bar:
            drawn = _run_tasks(_draw_chunk, tasks, pool, bar, sizes)
    except BaseException:
        if pool is not None:  # a failure or a signal: don't wait for the running fits
            _stop_pool(pool)
        raise
    else:
        if pool is not None:
            pool.shutdown(wait=True)
    finally:
        for end in watch or ():
            end.close()

    redraws = copies = 0
    lo = 0
    for samples, used, copied in drawn:
        rows = draw_rows[lo : lo + len(samples)]
        out[rows] = samples
        redraws += used
        copies += copied
        lo += len(samples)

    stats = fit_quality_summary([f.result for f in fits])
    stats.update(
        {
            "fit_seconds": float(fit_seconds),
            "fit_seconds_mean": float(np.mean([f.seconds for f in fits])) if fits else 0.0,
            "n_generated": int(m),
            "n_copied": int(copies + (m - len(draw_rows))),
            "n_redraws": int(redraws),
            "classes_copied": int(classes_copied),
            "n_classes": int(classes.size),
            "per_class": int(per_class),
        }
    )
    return AugmentResult(
        trajectories=out,
        labels=labels[np.asarray(plan_parent, dtype=np.int64)] if m else labels[:0].copy(),
        parent=np.asarray(plan_parent, dtype=np.int64),
        stats=stats,
    )
