"""CSV and Parquet tables: one row per sample (the default reader)."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path
from typing import Any

from . import Reader, Recording, register_reader

__all__ = ["TableReader"]


class TableReader(Reader):
    """CSV (comma-separated, header row) or Parquet, one row per sample.

    Options: ``time``, ``time_unit``, ``time_origin``, ``columns``, ``unit`` (see
    :func:`bvpnav.io.read_recording`).
    """

    name = "table"
    suffixes = (".csv", ".parquet", ".pq")
    options = frozenset({"time", "time_unit", "time_origin", "columns", "unit"})
    description = "CSV or Parquet, one row per sample (time column + acceleration or strapdown columns)"

    def sniff(self, head: bytes) -> bool:
        return True  # the default: every .csv / .parquet file is offered to it

    def read(self, path: Path, options: Mapping[str, Any]) -> Recording:
        from ..io import read_recording

        data = read_recording(path, dict(options))
        return Recording(t=data.t, source=str(path), time_origin=data.time_origin, acc=data.acc,
                         axes=data.axes)

    def example(self, folder: Path) -> Path:
        import numpy as np

        path = Path(folder) / "recording.csv"
        t = np.arange(11) * 0.1
        rows = (f"{float(a)!r},{float(b)!r}\n" for a, b in zip(t, np.sin(t), strict=True))
        path.write_text("t,acc_x\n" + "".join(rows))
        return path


register_reader(TableReader())
