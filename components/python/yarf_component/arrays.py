"""Batches in and out of the wire: yarf.v1.Array <-> numpy, with the input checks of yarfd."""

from __future__ import annotations

import numpy as np

from yarf.client import array_to_numpy, numpy_to_array
from yarf.v1 import component_pb2
from yarf_component.calls import invalid

# Largest batch one call may ask for, in values (as yarfd).
MAX_VALUES = 1 << 26


class Batch:
    """Decodes the FLOAT32 arrays of one request, which must share their row count."""

    def __init__(self) -> None:
        self.rows: int | None = None

    def floats(self, array: component_pb2.Array, name: str, *columns: int) -> np.ndarray:
        """``array`` as float32 [N, *columns]; INVALID_ARGUMENT naming it when it is not."""
        if array.dtype != component_pb2.Array.FLOAT32:
            raise invalid(f"{name}: expected a FLOAT32 array")
        expected = "[" + ", ".join(["N", *map(str, columns)]) + "]"
        if len(array.shape) != 1 + len(columns) or tuple(array.shape[1:]) != columns:
            raise invalid(f"{name}: expected shape {expected}, got {list(array.shape)}")
        try:
            values = array_to_numpy(array)
        except ValueError as error:
            raise invalid(f"{name}: {error}") from None
        if self.rows is not None and len(values) != self.rows:
            raise invalid(f"{name} has {len(values)} rows, the batch {self.rows}")
        self.rows = len(values)
        return values


def float32(values: object) -> component_pb2.Array:
    """A FLOAT32 Array of whatever a component returned, its shape unchecked."""
    return numpy_to_array(np.asarray(values, dtype=np.float32))


def uint32(values: object) -> component_pb2.Array:
    """A UINT32 Array of whatever a component returned, its shape unchecked."""
    return numpy_to_array(np.asarray(values, dtype=np.uint32))
