"""Variable layout of the sparse CMPC QP (paper eqs. 16-17; :mod:`.implicit_kd`).

States are decision variables next to the search directions, one block per stage::

    z = [x_0, dpc_0, df_0 (2x3), dtau_0 (2x3), dpf_0 (2x3),  ...,  x_h, dpc_h]
         12    3      6           6             6

so ``n = 33 h + 15`` for two feet.
"""

from __future__ import annotations

import numpy as np

from gaitnet_mpc.mpc.centroidal_model import N_FEET, NX

NU_STAGE = 3 + 3 * 3 * N_FEET  # dpc (3) + df, dtau, dpf per foot = 21
NS = NX + NU_STAGE  # variables per stage block = 33


class KDLayout:
    """Column indices of every variable group of a horizon of ``horizon`` stages.

    Attributes:
        n: number of variables.
        col_x: (h + 1, 12) columns of ``x_k``; col_pc: (h + 1, 3) of ``delta p_c,k``.
        col_f, col_tau, col_pf: (h, 2, 3) of ``delta f_i,k``, ``delta tau_i,k``,
            ``delta p_f,i,k``.
    """

    def __init__(self, horizon: int) -> None:
        self.horizon = h = int(horizon)
        self.n = NS * h + NX + 3
        stage = NS * np.arange(h + 1)[:, None]  # (h+1, 1) first column of each block
        self.col_x = stage + np.arange(NX)  # (h+1, 12) x_k
        self.col_pc = stage + NX + np.arange(3)  # (h+1, 3) dpc_k
        foot = 3 * np.arange(N_FEET)[:, None] + np.arange(3)  # (2, 3)
        self.col_f = stage[:h, :, None] + NX + 3 + foot  # (h, 2, 3) df_i,k
        self.col_tau = self.col_f + 3 * N_FEET  # dtau_i,k
        self.col_pf = self.col_f + 6 * N_FEET  # dpf_i,k

    def unpack(self, z: np.ndarray) -> dict[str, np.ndarray]:
        """Split a QP vector (n,) into ``states (h+1, 12)``, ``delta_p_com (h+1, 3)``,
        ``delta_f``, ``delta_tau``, ``delta_p_foot`` (h, 2, 3)."""
        h = self.horizon
        z = np.asarray(z, dtype=float)
        body = z[: NS * h].reshape(h, NS)
        tail = z[NS * h :]
        states = np.vstack([body[:, :NX], tail[:NX]])
        dpc = np.vstack([body[:, NX : NX + 3], tail[NX:]])
        u = body[:, NX + 3 :]
        return {
            "states": states,
            "delta_p_com": dpc,
            "delta_f": u[:, : 3 * N_FEET].reshape(h, N_FEET, 3),
            "delta_tau": u[:, 3 * N_FEET : 6 * N_FEET].reshape(h, N_FEET, 3),
            "delta_p_foot": u[:, 6 * N_FEET :].reshape(h, N_FEET, 3),
        }

    def pack(self, parts: dict[str, np.ndarray]) -> np.ndarray:
        """The QP vector (n,) of the parts that :meth:`unpack` returns."""
        h = self.horizon
        z = np.empty(self.n)
        body = z[: NS * h].reshape(h, NS)
        tail = z[NS * h :]
        body[:, :NX] = parts["states"][:h]
        tail[:NX] = parts["states"][h]
        body[:, NX : NX + 3] = parts["delta_p_com"][:h]
        tail[NX:] = parts["delta_p_com"][h]
        u = body[:, NX + 3 :]
        u[:, : 3 * N_FEET] = parts["delta_f"].reshape(h, 3 * N_FEET)
        u[:, 3 * N_FEET : 6 * N_FEET] = parts["delta_tau"].reshape(h, 3 * N_FEET)
        u[:, 6 * N_FEET :] = parts["delta_p_foot"].reshape(h, 3 * N_FEET)
        return z


__all__ = ["NS", "NU_STAGE", "KDLayout"]
