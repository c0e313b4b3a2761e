"""Tile pyramids sharded across a Dask cluster: ``build_pyramid``.

The shard plan (``cota.tiles_plan``, the same as ``cota tiles --plan``) becomes
one Dask task per shard through ``client.map``; each task writes its shard's
tiles with ``cota.tiles(..., shard=(i, n))`` (atomic writes, idempotent) and
its record file; the reduce (``cota.tiles_reduce``) runs as a final task that
depends on all shards and writes ``layer.json``. The output is byte-identical
to a single-process ``cota.tiles`` / ``cota tiles`` run with the same settings.

* **Resumable:** a shard whose record file exists is not submitted again.
* **Retries:** a failed or lost task is retried (``retries``); a worker killed
  mid-shard leaves only complete tiles (each written to a temporary file and
  renamed), which the retry skips.
* **Progress:** the tasks are ordinary Dask tasks, visible in the dashboard
  (named ``cota-shard-…`` and ``cota-reduce-…``).

The directory ``out`` must be reachable by every worker (a shared filesystem).
"""

from __future__ import annotations

import os
from typing import Any, Optional, Sequence, Union

from ._cota import shard_record, tiles, tiles_plan, tiles_reduce

_Path = Union[str, "os.PathLike[str]"]


def _shard(inputs: list, out: str, index: int, shards: int, settings: dict) -> dict:
    return tiles(inputs, out, shard=(index, shards), **settings)


def _reduce(done: list, out: str, shards: int) -> int:
    # ``done`` (the shards' reports) only orders this task after them.
    del done
    return tiles_reduce(out, shards)


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
    call), ``tiles`` (recorded by the shards). Raises what ``cota.tiles`` or
    ``cota.tiles_reduce`` raise.
    """
    if client is None:
        from distributed import get_client

        client = get_client()
    paths = [os.fspath(inputs)] if isinstance(inputs, (str, os.PathLike)) else [
        os.fspath(p) for p in inputs
    ]
    out = os.fspath(out)
    plan_keys = ("min_zoom", "max_zoom", "tile_cells", "error_factor", "max_error_m_at_max_zoom")
    plan = tiles_plan(paths, shards, **{k: v for k, v in settings.items() if k in plan_keys})
    todo = [p["shard"] for p in plan if not os.path.exists(shard_record(out, p["shard"], shards))]
    futures = client.map(
        _shard,
        [paths] * len(todo),
        [out] * len(todo),
        todo,
        [shards] * len(todo),
        [settings] * len(todo),
        key=[f"cota-shard-{i}-of-{shards}-{os.path.basename(out)}" for i in todo],
        retries=retries,
        pure=False,
    )
    reduced = client.submit(_reduce, futures, out, shards, retries=retries, pure=False,
                            key=f"cota-reduce-{shards}-{os.path.basename(out)}")
    tiles_done = reduced.result()
    return {"shards": shards, "skipped_shards": shards - len(todo), "tiles": tiles_done}
