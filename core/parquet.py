"""Reading parquet into pandas through pyarrow's own file system.

`pandas.read_parquet(path)` on Python 3.11 leaves arrow threads that call back into Python;
under load they race interpreter shutdown and abort the process ("terminate called without an
active exception") after all work is done. pyarrow's native reader does not.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pyarrow.parquet as pq


def read(path: Path | str) -> pd.DataFrame:
    """A parquet file, or a folder of them (read as one dataset), as a DataFrame."""
    return pq.read_table(str(path)).to_pandas()
