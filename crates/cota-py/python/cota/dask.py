"""Tile pyramids sharded across a Dask cluster: ``build_pyramid``.

Three kinds of Dask task, as ``cota tiles --plan`` / ``--shard I/N`` /
``--reduce``:

1. the **plan step** (``cota.tiles_plan_step``): reads every input once, writes
   the frame ``out/.cota-shards-N.json`` (where each input file lies in the
   mosaic, the lattice's statistics) and the band zoom's tile-corner heights;
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
  last); a shard whose record file exists is not submitted
  again.
* **Retries:** a failed or lost task is retried (``retries``); a worker killed
  mid-task leaves only complete tiles (each written to a temporary file and
  renamed), which the retry skips.
* **Progress:** the tasks are ordinary Dask tasks, visible in the dashboard
  (named ``cota-plan-…``, ``cota-shard-…`` and ``cota-reduce-…``).

The directory ``out`` and the inputs must be reachable by every worker (a
shared filesystem).
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence, Union

from ._cota import shard_frame, shard_record, tiles, tiles_plan_step, tiles_reduce

_Path = Union[str, "os.PathLike[str]"]


def _plan_step(inputs: list, out: str, shards: int, settings: dict) -> dict:
    return tiles_plan_step(inputs, out, shards, **settings)


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
    **settings: Any,
) -> dict:
    """Builds the pyramid of ``inputs`` under ``out`` on a Dask cluster.

    ``client``: a ``distributed.Client`` (default: the current one,
    ``distributed.get_client()``). ``shards``: the number of tasks.
    ``retries``: per task. ``settings``: the keyword arguments of
    ``cota.tiles`` that decide the tiles (``min_zoom``, ``max_zoom``,
    ``tile_cells``, ``error_factor``, ``max_error_m_at_max_zoom``,
    ``normals``, ``watermask``, ``metadata``, ``gzip``, ``check``).

    Returns a dict: ``shards``, ``skipped_shards`` (already done before this
    call), ``plan_step`` (``"ran"``, or ``"skipped"`` when its frame was there,
    or some shards were done without it: the others then run without it
    too), ``files_read`` (for each shard run here, the
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
    plan = None
    # The plan step runs on a fresh run; a resumed run whose finished shards
    # ran without it (no frame) goes on without it.
    if len(todo) == shards and not os.path.exists(shard_frame(out, shards)):
        future = client.submit(_plan_step, paths, out, shards, settings, retries=retries,
                               pure=False, key=f"cota-plan-{shards}-{name}")
        # A barrier, not a data dependency: shard tasks that took its result
        # would all queue on the worker holding it.
        plan = future.result()
        future.release()
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
        "files_read": dict(zip(todo, read)),
        "coarse_tiles": coarse,
        "tiles": tiles_done,
    }
