"""Tile pyramids sharded across a Dask cluster: ``build_pyramid``.

The Dask tasks, as ``cota tiles --plan [--layout | --part I]`` / ``--shard I/N``
/ ``--reduce``:

1. the **plan step**, itself in parts: the *layout* (``cota.tiles_plan_layout``:
   each input read alone for its shape, where each file lies in the mosaic),
   then one task per *plan part* (``cota.tiles_plan_part``, through
   ``client.map``: shard I's files read and its part resampled for the
   lattice's statistics and the band zoom's tile-corner heights), then the
   *merge* (``cota.tiles_plan_step``), which writes the frame
   ``out/.cota-shards-N.json`` and the band corners. An input whose shards
   must read every file (one file, voids) has no plan parts: the merge task
   reads the whole input;
2. one task per **shard** (``cota.tiles(..., shard=(i, n))``), after the plan
   step: it finds the frame, reads only the input files its part of the lattice
   needs and holds only that part; it writes its tiles of the band zoom and
   finer (atomic writes, idempotent), its partial maxima of the coarser tiles,
   and its record file;
3. the **reduce** (``cota.tiles_reduce``), after all shards: merges the partial
   maxima, cuts the tiles coarser than the band zoom (exactly the single-machine
   tiles), writes ``layer.json`` and removes the records, partials and frame.

The output is byte-identical to a single-process ``cota.tiles`` / ``cota tiles``
run with the same settings.

* **Resumable:** the plan step is skipped when its frame exists (it is written
  last); a plan part whose file exists is not computed again; a shard whose
  record file exists is not submitted again.
* **Retries:** a failed or lost task is retried (``retries``); a worker killed
  mid-task leaves only complete tiles (each written to a temporary file and
  renamed), which the retry skips.
* **Progress:** the tasks are ordinary Dask tasks, visible in the dashboard
  (named ``cota-layout-…``, ``cota-plan-part-…``, ``cota-plan-…``,
  ``cota-shard-…`` and ``cota-reduce-…``).

The directory ``out`` and the inputs must be reachable by every worker (a
shared filesystem).
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence, Union

from ._cota import (
    shard_frame,
    shard_record,
    tiles,
    tiles_plan_layout,
    tiles_plan_part,
    tiles_plan_step,
    tiles_reduce,
)

_Path = Union[str, "os.PathLike[str]"]

# The settings that decide the lattice and the plan (the plan parts' key).
_PLAN_SETTINGS = ("min_zoom", "max_zoom", "tile_cells", "error_factor", "max_error_m_at_max_zoom")


def _plan_layout(inputs: list, out: str, shards: int, settings: dict) -> dict:
    return tiles_plan_layout(inputs, out, shards, **settings)


def _plan_part(inputs: list, out: str, shards: int, part: int, settings: dict) -> dict:
    return tiles_plan_part(inputs, out, shards, part, **settings)


def _plan_step(parts: list, inputs: list, out: str, shards: int, settings: dict) -> dict:
    # ``parts`` (the plan parts' reports) orders this task after them: it
    # merges their files, computing any that is missing.
    return tiles_plan_step(inputs, out, shards, **settings)


def _run_plan_step(client: Any, paths: list, out: str, shards: int, retries: int,
                   in_parts: bool, settings: dict) -> tuple:
    """The layout, the plan parts (in parallel) and the merge; the client
    waits for the merge (a barrier, not a data dependency: shard tasks that
    took its result would all queue on the worker holding it)."""
    name = os.path.basename(out)
    plan_settings = {k: v for k, v in settings.items() if k in _PLAN_SETTINGS}
    parts = []
    streamed = False
    if in_parts:
        layout = client.submit(_plan_layout, paths, out, shards, plan_settings,
                               retries=retries, pure=False, key=f"cota-layout-{shards}-{name}")
        streamed = layout.result()["streamed"]
        layout.release()
    if streamed:
        parts = client.map(
            _plan_part,
            [paths] * shards,
            [out] * shards,
            [shards] * shards,
            range(shards),
            [plan_settings] * shards,
            key=[f"cota-plan-part-{i}-of-{shards}-{name}" for i in range(shards)],
            retries=retries,
            pure=False,
        )
    future = client.submit(_plan_step, parts, paths, out, shards, settings, retries=retries,
                           pure=False, key=f"cota-plan-{shards}-{name}")
    plan = future.result()
    future.release()
    for p in parts:
        p.release()
    return plan, len(parts)


def _shard(inputs: list, out: str, index: int, shards: int, settings: dict) -> dict:
    return tiles(inputs, out, shard=(index, shards), **settings)


def _reduce(done: list, out: str, shards: int) -> tuple:
    # ``done`` (the shards' reports) orders this task after them; their
    # reports are taken here, not gathered after the reduce (a lost result
    # recomputed then would write a record again after the reduce removed it).
    return tiles_reduce(out, shards), [r["files_read"] for r in done]


def build_pyramid(
    inputs: Union[_Path, Sequence[_Path]],
    out: _Path,
    client: Optional[Any] = None,
    shards: int = 4,
    retries: int = 2,
    plan_in_parts: bool = True,
    **settings: Any,
) -> dict:
    """Builds the pyramid of ``inputs`` under ``out`` on a Dask cluster.

    ``client``: a ``distributed.Client`` (default: the current one,
    ``distributed.get_client()``). ``shards``: the number of tasks.
    ``retries``: per task. ``plan_in_parts``: run the plan step as a layout
    task, one plan-part task per shard and a merge task (default), or as one
    task reading the parts in turn. ``settings``: the keyword arguments of
    ``cota.tiles`` that decide the tiles (``min_zoom``, ``max_zoom``,
    ``tile_cells``, ``error_factor``, ``max_error_m_at_max_zoom``,
    ``normals``, ``watermask``, ``metadata``, ``gzip``, ``check``).

    Returns a dict: ``shards``, ``skipped_shards`` (already done before this
    call), ``plan_step`` (``"ran"``, or ``"skipped"`` when its frame was there,
    or some shards were done without it: the others then run without it
    too), ``plan_parts`` (plan-part tasks run: ``shards``, or 0 when the plan
    step was skipped or reads the whole input), ``files_read`` (for each shard run here, the
    input files it read), ``coarse_tiles`` (the tiles coarser than the band
    zoom, cut by the reduce; None when the plan step was skipped),
    ``tiles`` (in the pyramid: the shards' tiles plus the coarser ones). Raises what ``cota.tiles``, ``cota.tiles_plan_step`` or
    ``cota.tiles_reduce`` raise.
    """
    if client is None:
        from distributed import get_client

        client = get_client()
    paths = [os.fspath(inputs)] if isinstance(inputs, (str, os.PathLike)) else [
        os.fspath(p) for p in inputs
    ]
    out = os.fspath(out)
    name = os.path.basename(out)
    todo = [i for i in range(shards) if not os.path.exists(shard_record(out, i, shards))]
    # The two outer shards are the smallest (their part has a margin on one
    # side only): submitted last, they fill the gaps at the end instead of
    # leaving one worker finishing a large shard alone.
    todo.sort(key=lambda i: i in (0, shards - 1))
    plan, plan_parts = None, 0
    # The plan step runs on a fresh run; a resumed run whose finished shards
    # ran without it (no frame) goes on without it.
    if len(todo) == shards and not os.path.exists(shard_frame(out, shards)):
        plan, plan_parts = _run_plan_step(client, paths, out, shards, retries, plan_in_parts,
                                          settings)
    futures = client.map(
        _shard,
        [paths] * len(todo),
        [out] * len(todo),
        todo,
        [shards] * len(todo),
        [settings] * len(todo),
        key=[f"cota-shard-{i}-of-{shards}-{name}" for i in todo],
        retries=retries,
        pure=False,
    )
    reduced = client.submit(_reduce, futures, out, shards, retries=retries, pure=False,
                            key=f"cota-reduce-{shards}-{name}")
    tiles_done, read = reduced.result()
    coarse = plan["coarse_tiles"] if plan is not None else None
    return {
        "shards": shards,
        "skipped_shards": shards - len(todo),
        "plan_step": "skipped" if plan is None else "ran",
        "plan_parts": plan_parts,
        "files_read": dict(zip(todo, read)),
        "coarse_tiles": coarse,
        "tiles": tiles_done,
    }
