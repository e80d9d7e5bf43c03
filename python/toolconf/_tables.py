"""Tools in memory as the native module takes them: (column name, 1-D values) pairs.

pandas is never imported here: a DataFrame can only exist once its user has imported pandas,
so ``sys.modules`` tells whether an object may be one.
"""

import os
import sys
from collections.abc import Mapping

import numpy as np

DATAFRAME_SOURCE = "tools DataFrame"
ARRAY_SOURCE = "tools array"
DICT_SOURCE = "tools dict"


def is_dataframe(tools) -> bool:
    pandas = sys.modules.get("pandas")
    return pandas is not None and isinstance(tools, pandas.DataFrame)


def frame_column(series):
    """A DataFrame column as a NumPy array: numbers as float64 with NaN for missing values
    (nullable and masked dtypes included); anything else as objects with None for missing."""
    if series.dtype.kind in "fiu":
        return series.to_numpy(dtype="float64", na_value=np.nan)
    return series.to_numpy(dtype=object, na_value=None)


def frame_columns(frame):
    """A DataFrame's columns as pairs, in order (a name given twice stays twice, so that the
    native reader refuses it as it refuses a file's header)."""
    return [(name, frame_column(frame.iloc[:, k])) for k, name in enumerate(frame.columns)]


def native_tools(tools):
    """``(tools, source, was_a_dataframe)``: a path as it is; a DataFrame, a structured array
    or a mapping as columns, with the name errors give them."""
    if isinstance(tools, (str, os.PathLike)):
        return tools, None, False
    if is_dataframe(tools):
        return frame_columns(tools), DATAFRAME_SOURCE, True
    if isinstance(tools, np.ndarray) and tools.dtype.names is not None:
        return [(name, tools[name]) for name in tools.dtype.names], ARRAY_SOURCE, False
    if isinstance(tools, Mapping):
        return tools, DICT_SOURCE, False
    return tools, None, False
