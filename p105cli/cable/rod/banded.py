"""LAPACK band storage of the block-tridiagonal systems of the Newton step.
"""

from __future__ import annotations

from functools import lru_cache

import numpy as np


@lru_cache(maxsize=64)
def _band_map(nblk: int, b: int, kl: int, ku: int, extra: int):
    """Flat target/source indices that scatter block-tridiagonal (D, U, U^T) into LAPACK band storage.

    Storage: A[i, j] at ab[extra + ku + i - j, j] (``extra = kl`` for dgbsv,
    ``0`` with ``kl = 0`` for the upper form of dpbtrf). Returns
    (tD, sD, tU, sU, tL, sL, shape).
    """
    N = nblk * b
    nrow = extra + ku + kl + 1
    r, c = np.meshgrid(np.arange(b), np.arange(b), indexing="ij")
    blk = np.arange(nblk)[:, None, None]
    out = []
    for (I, J) in (
        (blk * b + r, blk * b + c),                            # D_i
        ((blk[:-1]) * b + r, (blk[:-1] + 1) * b + c),         # U_i: block i rows, i+1 cols
        ((blk[:-1] + 1) * b + c, (blk[:-1]) * b + r),         # U_i^T: block i+1 rows, i cols
    ):
        d = I - J
        ok = (d >= -ku) & (d <= kl)
        tgt = (extra + ku + d) * N + J
        out.append(tgt[ok])
        out.append(np.flatnonzero(ok.ravel()))
    out.append((nrow, N))
    return tuple(out)


def _to_band(D, U, kl, ku, extra):
    nblk, b = D.shape[0], D.shape[1]
    tD, sD, tU, sU, tL, sL, shape = _band_map(nblk, b, kl, ku, extra)
    ab = np.zeros(shape)
    flat = ab.reshape(-1)
    flat[tD] = D.reshape(-1)[sD]
    if nblk > 1:
        flat[tU] = U.reshape(-1)[sU]
        flat[tL] = U.reshape(-1)[sL]
    return ab
