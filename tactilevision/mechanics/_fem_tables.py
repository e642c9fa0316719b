"""Read the project's FEM tables (``models/kappa_fem.npz``, ``models/beta_fem.npz``).

Built by ``tactilevision fem tables`` (:mod:`tactilevision.fem._tables`); read
here with numpy alone, once per process.
"""

from __future__ import annotations

import json
from functools import lru_cache

import numpy as np

from .._assets import asset_dir
from .._checks import InputError
from ._kappa import KappaTable

__all__ = ["fem_kappa_table", "fem_table_meta"]


@lru_cache(maxsize=4)
def _load(name: str) -> dict:
    path = asset_dir("models") / name
    if not path.is_file():
        raise InputError(f"the FEM table {path} is missing: rebuild it with "
                         "'tactilevision fem tables'")
    with np.load(path, allow_pickle=False) as z:
        data = {k: z[k] for k in z.files}
    data["meta"] = json.loads(data["meta"].tobytes().decode())
    data["path"] = str(path)
    return data


def fem_table_meta(name: str = "kappa_fem.npz") -> dict:
    """Provenance record of a stored FEM table (command, mesh, versions, date)."""
    return dict(_load(name)["meta"])


@lru_cache(maxsize=4)
def fem_kappa_table(contact: str = "frictionless") -> KappaTable:
    """The FEM kappa(nu, a/h) table for one punch condition.

    Parameters
    ----------
    contact : {'frictionless', 'bonded'}, default 'frictionless'

    Returns
    -------
    table : KappaTable

    Raises
    ------
    InputError
        If the table file is missing or lacks the contact.
    """
    data = _load("kappa_fem.npz")
    contacts = [str(c) for c in data["contacts"]]
    if contact not in contacts:
        raise InputError(f"contact must be one of {contacts}, got {contact!r}")
    meta = data["meta"]
    return KappaTable(
        a_over_h=data["a_over_h"].astype(np.float64),
        nu=data["nu"].astype(np.float64),
        values=np.ascontiguousarray(data["kappa"][contacts.index(contact)], np.float64),
        source=(f"tactilevision FEM, {contact} punch, small strain ({meta['solver']}; mesh "
                f"{meta['mesh']}; built {meta.get('created', '?')} by "
                f"'{meta.get('command', '?')}')"),
        doi="",
    )
