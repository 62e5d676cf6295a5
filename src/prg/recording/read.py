"""Reading a recording back: its entities, row counts, times and component values.

The functions read a file with :class:`rerun.chunk.RrdReader` (part of ``rerun-sdk`` itself
since 0.41, no extra needed); the tests use them.
"""

from __future__ import annotations

import os
from collections import defaultdict
from collections.abc import Iterator
from pathlib import Path
from typing import Any

import numpy as np
import rerun as rr

from prg.errors import UsageError

_INTERNAL_ENTITY_PREFIX = "__"  # Rerun's own entities (recording properties)


def _chunks(path: str | os.PathLike, blueprint: bool = False) -> Iterator:
    """The chunks of the first recording store in ``path`` (or of its first blueprint)."""
    from rerun.chunk import RrdReader

    path = Path(path)
    if not path.is_file():
        raise UsageError(f"{path}: no such recording file")
    try:
        reader = RrdReader(path)
        stores = reader.blueprints() if blueprint else [None]
        if not stores:
            raise ValueError("it holds no blueprint")
        chunks = list(reader.stream(store=stores[0]).to_chunks())
    except (OSError, ValueError, RuntimeError) as err:
        raise UsageError(f"{path}: not a readable Rerun recording ({err})") from None
    yield from chunks


def _entity(chunk) -> str:
    return chunk.entity_path.lstrip("/")


def read_entities(path: str | os.PathLike) -> dict[str, set[str]]:
    """Entity paths in a recording and the components and archetypes logged on each.

    Parameters
    ----------
    path : path-like
        An ``.rrd`` file.

    Returns
    -------
    dict of str to set of str
        Entity path without the leading ``/`` (as logged, e.g. ``"word/target"``) to the names
        found there: components as ``"Archetype:field"`` (``"LineStrips2D:strips"``) and the
        archetypes' short names (``"LineStrips2D"``). Rerun's own entities (``/__properties``)
        are left out.

    Raises
    ------
    UsageError
        If the file is missing or not a Rerun recording.
    """
    found: dict[str, set[str]] = defaultdict(set)
    for chunk in _chunks(path):
        entity = _entity(chunk)
        if entity.startswith(_INTERNAL_ENTITY_PREFIX):
            continue
        for field in chunk.to_record_batch().schema:
            meta = field.metadata or {}
            if meta.get(rr.RERUN_KIND) != b"data":
                continue
            found[entity].add(meta.get(b"rerun:component", field.name.encode()).decode())
            archetype = meta.get(b"rerun:archetype")
            if archetype:
                found[entity].add(archetype.decode().rsplit(".", 1)[-1])
    return dict(found)


def recording_summary(path: str | os.PathLike) -> dict[str, dict[str, int]]:
    """Row counts per entity and timeline.

    Returns
    -------
    dict of str to dict of str to int
        Entity path (as in :func:`read_entities`) to ``{timeline: rows}``, with static rows
        counted under ``"static"``.
    """
    rows: dict[str, dict[str, int]] = defaultdict(lambda: defaultdict(int))
    for chunk in _chunks(path):
        entity = _entity(chunk)
        if entity.startswith(_INTERNAL_ENTITY_PREFIX):
            continue
        timelines = ["static"] if chunk.is_static else chunk.timeline_names
        for timeline in timelines:
            rows[entity][timeline] += chunk.num_rows
    return {entity: dict(counts) for entity, counts in rows.items()}


def read_times(path: str | os.PathLike, entity: str, timeline: str) -> np.ndarray:
    """The sorted times of an entity's rows on a timeline.

    Returns
    -------
    ndarray, shape (rows,)
        Seconds (float) for duration timelines, raw integers for sequence timelines.
    """
    import pyarrow as pa

    values = []
    for chunk in _chunks(path):
        if _entity(chunk) != entity.lstrip("/") or timeline not in chunk.timeline_names:
            continue
        column = chunk.to_record_batch().column(timeline)
        if pa.types.is_duration(column.type) or pa.types.is_timestamp(column.type):
            values.append(column.cast(pa.int64()).to_numpy() / 1e9)
        else:
            values.append(column.to_numpy())
    return np.sort(np.concatenate(values)) if values else np.empty(0)


def read_component(
    path: str | os.PathLike, entity: str, component: str, timeline: str | None = None
) -> list:
    """The rows of one component of one entity, as Python values.

    Parameters
    ----------
    path : path-like
    entity : str
        As in :func:`read_entities` (a leading ``/`` is ignored).
    component : str
        ``"Archetype:field"``, e.g. ``"Points2D:positions"``.
    timeline : str, optional
        Sort the temporal rows by this timeline (rows not on it keep file order, last).

    Returns
    -------
    list
        One entry per row (each a list of the row's instances): static rows first.
    """
    import pyarrow as pa

    static: list = []
    timed: list[tuple[int, int, object]] = []
    for chunk in _chunks(path):
        if _entity(chunk) != entity.lstrip("/"):
            continue
        batch = chunk.to_record_batch()
        if component not in batch.schema.names:
            continue
        values = batch.column(component).to_pylist()
        if chunk.is_static:
            static.extend(values)
            continue
        if timeline is not None and timeline in chunk.timeline_names:
            keys = batch.column(timeline).cast(pa.int64()).to_pylist()
            rank = 0
        else:
            keys, rank = [0] * len(values), 1
        timed.extend((rank, key, value) for key, value in zip(keys, values))
    if timeline is not None:
        timed.sort(key=lambda row: row[:2])
    return static + [value for _, _, value in timed]


def read_views(path: str | os.PathLike) -> dict[str, dict[str, Any]]:
    """The views of a recording's default blueprint and their settings, by display name.

    Returns
    -------
    dict of str to dict of str to object
        View name (``"Joint angles (rad)"``) to ``"class"`` (``"3D"``, ``"2D"``,
        ``"TimeSeries"`` ...), ``"origin"`` and each setting the blueprint gives it as
        ``"Archetype:field"`` with its value as Python data: ``"EyeControls3D:position"`` (a
        list of 3 floats), ``"VisualBounds2D:range"`` (``{"x_range": [lo, hi], "y_range":
        ...}``), ``"PlotLegend:corner"`` (:class:`rerun.blueprint.Corner2D`'s value),
        ``"TimeAxis:view_range"`` (``{"start": ns, "end": ns}``) ...

    Raises
    ------
    UsageError
        If the file is missing, not a Rerun recording or has no blueprint.
    """
    names = {"ViewBlueprint:display_name": "name", "ViewBlueprint:class_identifier": "class"}
    names["ViewBlueprint:space_origin"] = "origin"
    views: dict[str, dict[str, Any]] = defaultdict(dict)
    for chunk in _chunks(path, blueprint=True):
        parts = chunk.entity_path.strip("/").split("/")
        if parts[0] != "view" or len(parts) > 3:  # settings, not containers or overrides
            continue
        batch = chunk.to_record_batch()
        for field in batch.schema:
            if (field.metadata or {}).get(rr.RERUN_KIND) != b"data":
                continue
            value = batch.column(field.name).to_pylist()[-1][0]
            views[parts[1]][names.get(field.name, field.name)] = value
    return {view.pop("name"): view for view in views.values() if "name" in view}
