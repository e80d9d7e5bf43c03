"""toolconf on a Dask cluster: ``rank``, ``simulate_batch`` and ``reproduce`` for studies one
machine is too small for, with the same results as ``toolconf.rank``,
``toolconf.simulate_batch`` and ``toolconf.reproduce``.

An optional extra (``pip install "./python[dask]"``: dask's dataframe and distributed). Both
functions run on whatever cluster the ``distributed.Client`` given (or the current one) points
at; every worker needs this package installed, as the client has it.

``rank(ddf, task, screen=K)`` is ``toolconf.rank`` cut where its data can travel, each piece
the native library's own code:

1. each partition's row count, so that every row has its global number (the ``row`` column and
   the messages);
2. the cheap stage, partition by partition on the workers: each partition's rows checked as a
   tools file's are, its ln|Π^U| (and with ``screen_by="predicted"`` its predicted cost)
   computed, its K best by the screen's criterion kept (with their predictions);
3. on the client, the partitions' screens absorbed in row order: the global K best by the same
   keys, ties and tools without a prediction in global row order, and the whole table's
   checks;
4. the K kept tools' episodes, in blocks spread over the workers (without a screen, each
   partition's episodes run where the partition is);
5. on the client, the simulated blocks ranked into one table.

So the result is ``toolconf.rank`` on the concatenated rows, row for row and digit for digit,
and a bad row raises the same ``ValueError`` (the first bad row in row order).

``reproduce(model, task, tools=... | sample=N)`` is ``toolconf.reproduce`` in three steps: the
population drawn (or read) on the client, every tool's episodes in blocks of tools on the
workers (each record's numbers travel as their bits), and the trials, statistics and verdicts
on the client: the same tables and verdicts, number for number.

Workers run each block's episodes on rayon's threads: set ``RAYON_NUM_THREADS`` in the workers'
environment to their share of the cores (``LocalCluster(..., env={"RAYON_NUM_THREADS": "1"})``
with one thread per worker), or the processes of one machine compete for its cores.

A model library loaded on the client (``toolconf.load_model``) is loaded on each worker before
its first block, from the same path: on a cluster of several machines, that path must reach the
same library on every one of them (a shared file system, or the same build at the same place).
"""

import math
import operator
import warnings
from typing import TYPE_CHECKING, Any, Literal, Optional

import numpy as np

from . import _COUNTS, _LOADED, _box_texts, _ensure_loaded, _evaluation, _toolconf, _wants_frames
from ._tables import DATAFRAME_SOURCE, frame_columns, native_tools

if TYPE_CHECKING:
    import dask.dataframe
    import distributed
    import pandas

    from ._toolconf import Columns, Task

__all__ = ["rank", "reproduce", "simulate_batch"]


def _client(client):
    if client is not None:
        return client
    import distributed

    try:
        return distributed.default_client()
    except ValueError:
        # distributed's message is five lines; the package's errors are one.
        raise ValueError("client = None and no distributed.Client is running: start one "
                         "(distributed.Client(cluster)) or pass client=") from None


def _threads(client) -> int:
    return max(1, sum(client.nthreads().values()))


# What runs on the workers: module-level functions, so that they pickle by name.


def _partition_length(frame) -> int:
    return len(frame)


def _screen_partition(frame, task, first_row, screen, skip_bad_rows, objective, screen_by,
                      loaded):
    _ensure_loaded(loaded)
    return _toolconf._screen_block(frame_columns(frame), task, first_row, screen,
                                   skip_bad_rows, DATAFRAME_SOURCE, objective, screen_by)


def _counts(block):
    return {key: value for key, value in block.items() if key != "kept"}


def _episodes(block, task, objective, method, loaded):
    _ensure_loaded(loaded)
    return _toolconf._episodes(block, task, objective, method)


def _kept_episodes(screened, task, objective, method, loaded):
    _ensure_loaded(loaded)
    return _toolconf._episodes(screened["kept"], task, objective, method)


def _batch(model, params, task, perturbations, method, first_tool, episode_options, loaded):
    _ensure_loaded(loaded)
    # The private twin of toolconf.simulate_batch: it also reads a task file sent as text.
    return _toolconf._simulate_batch(model, params, task, perturbations, method, first_tool,
                                     **episode_options)


def _reproduce_block(model, task, params, first, plan, method, loaded):
    _ensure_loaded(loaded)
    return _toolconf._reproduce_block(model, task, params, first, plan, method)


def _slice(block, start, stop):
    return {key: values[start:stop] for key, values in block.items()}


def _blocks(n, per_block):
    return [(start, min(start + per_block, n)) for start in range(0, n, per_block)]


def _per_block(name, value):
    """A block size given by the caller (``tools_per_task``, ``episodes_per_task``): None (the
    default) or an integer ≥ 1, else ``TypeError`` or ``ValueError`` naming it, as the native
    functions check their integer arguments."""
    if value is None:
        return None
    if isinstance(value, (bool, np.bool_)):
        raise TypeError(f"{name} = {value!r}: expected an integer, not a bool")
    try:
        value = operator.index(value)
    except TypeError:
        raise TypeError(f"{name} = {_short(value)}: expected an integer") from None
    if value < 1:
        raise ValueError(f"{name} = {value}: must be at least 1")
    return value


def _short(value):
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def rank(
    ddf: "dask.dataframe.DataFrame",
    task: "Task",
    screen: Optional[int] = None,
    objective: Literal["free-energy", "cost-j", "confidence"] = "free-energy",
    skip_bad_rows: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    *,
    screen_by: Optional[Literal["predicted", "confidence"]] = None,
    client: Optional["distributed.Client"] = None,
    episodes_per_task: Optional[int] = None,
) -> "pandas.DataFrame":
    """``toolconf.rank`` of a ``dask.dataframe.DataFrame`` of tools on a Dask cluster.

    The cheap stage runs partition by partition on the workers; the global ``screen`` best tools
    by ``screen_by`` (ties, and tools without a prediction, in the row order of the whole frame)
    are kept, and their episodes are spread over the workers. The result is
    ``toolconf.rank(ddf.compute(), task, ...)``, row for row and digit for digit (``row`` is the
    1-based place in the whole frame), whatever the partitioning, with the same warnings.

    Args:
        ddf: a dask DataFrame with a tools file's columns (``name``, ``model``, the models'
            parameters). It is read twice: once for its partitions' lengths, once for the
            screen (``ddf.persist()`` first if reading it is expensive).
        task, screen, objective, skip_bad_rows, method, screen_by: as ``toolconf.rank``. A
            task file is read here and sent to the workers as text.
        client: the ``distributed.Client`` to run on (default: the current one).
        episodes_per_task: how many episodes one cluster task runs (each on its worker's rayon
            threads), an integer ≥ 1; by default the kept tools are cut into about four blocks
            per worker thread. Without a screen each partition is one block.

    Returns:
        pandas.DataFrame: ``toolconf.rank``'s columns, best first.

    Raises:
        ValueError: as ``toolconf.rank``, for the first bad row in row order; an
            ``episodes_per_task`` below 1.
        TypeError: as ``toolconf.rank``; an ``episodes_per_task`` that is not an integer.
    """
    import pandas
    from dask import delayed

    episodes_per_task = _per_block("episodes_per_task", episodes_per_task)

    if not hasattr(ddf, "to_delayed"):
        raise ValueError(f"ddf = {type(ddf).__name__}: toolconf.dask.rank takes a dask DataFrame "
                         "(dask.dataframe.from_pandas(frame, npartitions=...)); toolconf.rank "
                         "takes a pandas DataFrame")
    client = _client(client)
    loaded = tuple(_LOADED)
    given = task
    task = _toolconf._portable_task(task, screen, objective, method, screen_by)
    parts = ddf.to_delayed()
    lengths = client.gather(client.compute([delayed(_partition_length)(p) for p in parts]))
    if sum(lengths) == 0:
        # No rows: toolconf.rank's own refusal of the empty frame (its columns checked first).
        from . import rank as local_rank

        return local_rank(ddf._meta, given, screen, objective, skip_bad_rows, method,
                          screen_by=screen_by)
    first_rows = np.concatenate([[1], 1 + np.cumsum(lengths)[:-1]]).tolist()
    screened = client.compute([
        delayed(_screen_partition)(p, task, first, screen, skip_bad_rows, objective, screen_by,
                                   loaded)
        for p, first in zip(parts, first_rows)
    ])
    if screen is None:
        # Only the counts come to the client; each partition's tools stay where they are.
        counts = _in_order(client, [client.submit(_counts, s) for s in screened])
    else:
        counts = _in_order(client, screened)
    for block in counts:
        for warning in block["skipped"]:
            warnings.warn(warning, UserWarning, stacklevel=2)
    kept, note = _toolconf._merge_screens(counts, task, screen, DATAFRAME_SOURCE, objective,
                                          screen_by)
    if note is not None:
        warnings.warn(note, UserWarning, stacklevel=2)
    if screen is None:
        simulated = [client.submit(_kept_episodes, s, task, objective, method, loaded) for s in screened]
    else:
        n = len(kept["row"])
        per_block = episodes_per_task or max(1, math.ceil(n / (4 * _threads(client))))
        simulated = [
            client.submit(_episodes, _slice(kept, a, b), task, objective, method, loaded)
            for a, b in _blocks(n, per_block)
        ]
    return pandas.DataFrame(_toolconf._rank_table(client.gather(simulated)))


def _in_order(client, futures):
    """The futures' results; if any failed, the first one's error in their order (a bad row
    of an earlier partition before a later one's, as a file is read)."""
    import distributed

    distributed.wait(futures)
    for future in futures:
        if future.status == "error":
            future.result()
    return client.gather(futures)


def simulate_batch(
    model: str,
    params: Any,
    task: "Task",
    perturbations: Any = None,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    *,
    client: Optional["distributed.Client"] = None,
    tools_per_task: Optional[int] = None,
    **episode_options: Any,
) -> "Columns":
    """``toolconf.simulate_batch`` on a Dask cluster: the tools cut into blocks of rows, each
    block's (tool, perturbation) episodes run on a worker, the rows put back in order.

    The result equals ``toolconf.simulate_batch(model, params, task, perturbations, method,
    **episode_options)`` entry for entry (``tool`` indexes the whole ``params``).

    Args:
        model, task, perturbations, method, episode_options: as ``toolconf.simulate_batch``.
        params: a 2-D NumPy array (one tool per row), or a ``dask.array`` whose row chunks are
            the blocks.
        client: the ``distributed.Client`` to run on (default: the current one).
        tools_per_task: the tools of one block (NumPy ``params``), an integer ≥ 1; by default
            about four blocks per worker thread.

    Returns:
        dict of arrays and the ``error`` list, as ``toolconf.simulate_batch``.

    Raises:
        ValueError: as ``toolconf.simulate_batch`` (the first bad tool in row order); a
            ``tools_per_task`` below 1.
        TypeError: as ``toolconf.simulate_batch``; a ``tools_per_task`` that is not an integer.
    """
    tools_per_task = _per_block("tools_per_task", tools_per_task)
    client = _client(client)
    loaded = tuple(_LOADED)
    task = _toolconf._portable_task(task, None, "free-energy", method)
    blocks, shape, dtype = _param_blocks(client, params, tools_per_task)
    # Everything but the tools' values is checked here, before the cluster runs anything: on
    # no tools of the same dtype, and if that fails, again on tools of the real shape, whose
    # check fails at the same place (before any episode) with the message
    # toolconf.simulate_batch would give.
    try:
        empty = _toolconf._simulate_batch(model, np.empty((0, shape[1]), dtype=dtype), task,
                                          perturbations, method, **episode_options)
    except ValueError:
        _toolconf._simulate_batch(model, np.broadcast_to(np.zeros((), dtype), shape), task,
                                  perturbations, method, **episode_options)
        raise
    if shape[0] == 0:
        return empty
    futures, first = [], 0
    for block, rows in blocks:
        futures.append(client.submit(_batch, model, block, task, perturbations, method, first,
                                     episode_options, loaded))
        first += rows
    parts = _in_order(client, futures)
    return {key: (sum((p[key] for p in parts), []) if key == "error"
                  else np.concatenate([p[key] for p in parts]))
            for key in parts[0]}


def _param_blocks(client, params, tools_per_task):
    """``([(block, rows), ...], shape, dtype)``: a dask array's row chunks (as futures), or a
    NumPy array cut into blocks of ``tools_per_task`` rows. The dtype stays the caller's, so
    that the native check refuses a complex or boolean array as toolconf.simulate_batch does."""
    if hasattr(params, "to_delayed") and hasattr(params, "chunks"):
        if params.ndim != 2:
            raise ValueError(f"params of shape {list(params.shape)}: a dask array of tools is "
                             "2-D, one tool per row")
        params = params.rechunk({1: -1})
        futures = client.compute(list(params.to_delayed()[:, 0]))
        return list(zip(futures, params.chunks[0])), params.shape, params.dtype
    array = np.asarray(params)
    if array.ndim != 2:
        raise ValueError(f"params of shape {list(array.shape)}: toolconf.dask.simulate_batch "
                         "takes a 2-D array, one tool per row")
    n = array.shape[0]
    per_block = tools_per_task or max(1, math.ceil(n / (4 * _threads(client))))
    return [(array[a:b], b - a) for a, b in _blocks(n, per_block)], array.shape, array.dtype


def reproduce(
    model: str,
    task: "Task",
    tools: Any = None,
    sample: Optional[int] = None,
    *,
    seed: int = 0,
    box: Optional[dict] = None,
    quick: bool = False,
    method: Literal["fast", "explicit", "auto", "stiff"] = "fast",
    frames: Optional[bool] = None,
    client: Optional["distributed.Client"] = None,
    tools_per_task: Optional[int] = None,
    **counts: Optional[int],
) -> dict:
    """``toolconf.reproduce`` on a Dask cluster: the population's episodes in blocks of tools on
    the workers, the rest on the client. The result equals ``toolconf.reproduce(model, task,
    tools, sample, ...)`` table for table and number for number.

    Args:
        model, task, tools, sample, seed, box, quick, method, frames, counts: as
            ``toolconf.reproduce``; ``tools`` may also be a dask DataFrame (computed on the
            client: a population is at most 10⁶ tools). A task file is read here and sent to
            the workers as text.
        client: the ``distributed.Client`` to run on (default: the current one).
        tools_per_task: the tools of one block, an integer ≥ 1; by default about four blocks
            per worker thread.

    Returns:
        dict: as ``toolconf.reproduce``.

    Raises:
        ValueError, TypeError, RuntimeError: as ``toolconf.reproduce``; a ``tools_per_task``
            below 1 (ValueError) or not an integer (TypeError).
    """
    tools_per_task = _per_block("tools_per_task", tools_per_task)
    unknown = sorted(set(counts) - set(_COUNTS))
    if unknown:
        raise TypeError(f"reproduce() got an unexpected keyword argument '{unknown[0]}'")
    client = _client(client)
    loaded = tuple(_LOADED)
    if hasattr(tools, "to_delayed") and hasattr(tools, "compute"):
        tools = tools.compute()
    native, source, frame = (None, None, False) if tools is None else native_tools(tools)
    plan = _toolconf._reproduce_plan(quick, counts)
    task = _toolconf._portable_task(task, None, "free-energy", method)
    population = _toolconf._reproduce_population(model, native, sample, seed, _box_texts(box), source)
    # The task checked on the client, before the cluster runs anything.
    _toolconf._reproduce_block(model, task, [], 0, plan, method)
    params = population["params"]
    per_block = tools_per_task or max(1, math.ceil(len(params) / (4 * _threads(client))))
    futures = [
        client.submit(_reproduce_block, model, task, params[a:b], a, plan, method, loaded)
        for a, b in _blocks(len(params), per_block)
    ]
    records = [record for block in _in_order(client, futures) for record in block]
    out = _toolconf._reproduce_finish(model, task, population, records, seed, plan, method)
    return _evaluation(out, _wants_frames(frames) or frame)
