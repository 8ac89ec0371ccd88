"""Per-point profiles in a compact netCDF file, readable without sweep.

``sweep export STORE --profiles FILE.nc`` (and ``herman2019 record`` for each shard of the
shipped grid) writes, for every stored point with results, its profiles along the floe
index from the ice edge: a/a0 and its standard error, the time-mean floe centre x, the
mean gap to the next floe and the fraction of time in contact with it. The file is
netCDF-4 with CF-1.10 attributes (``units``, ``long_name``, NaN ``_FillValue``), so

    import xarray as xr
    ds = xr.open_dataset("profiles-0-of-16.nc")     # h5netcdf or netCDF4 installed

reads it with xarray alone. Dimensions ``point`` (one per stored point, in the order of
the shard's table) and ``floe`` (as long as the longest sheet; a shorter sheet's tail is
NaN, ``n_floes`` says where it ends). The seven swept parameters, ``hash`` and ``status``
are coordinates along ``point``. Profile values are stored as float32 (a relative
rounding of 6e-8, far below every standard error); the shard's CSV table keeps the
scalars in full precision.

:func:`load_profiles_file` reads one such file, or every ``*.nc`` file of a directory
(the shards of one campaign), as one Dataset along ``point``, optionally selecting
points by parameter value; ``sweep.load_profiles`` calls it for a ``.nc`` path or a
directory.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd
import xarray as xr

import floewave
from floewave.paths import output_file_problem
from sweep.errors import ConfigError, PointNotFoundError, StoreError

__all__ = ["PROFILE_FILE_VARS", "PROFILE_STORE_VARS", "ENCODING", "check_profiles_output",
           "profiles_dataset", "load_profiles_file"]

#: The shipped profiles: name -> (units, long_name).
PROFILE_FILE_VARS: dict[str, tuple[str, str]] = {
    "a_rel": ("1", "wave amplitude at the floe over the incident amplitude, a/a0"),
    "a_rel_stderr": ("1", "standard error of a/a0 (jackknife over the ensemble's replicas)"),
    "gap_mean": ("m", "time-mean gap to the next floe (NaN for the last floe)"),
    "contact_fraction": ("1", "fraction of time in contact with the next floe (NaN for the"
                              " last floe)"),
}
#: The parameters carried along ``point`` when the store does not name its swept ones.
PARAMETERS = ("L_x", "T", "a0", "C_sd", "eps", "d_f", "dispersion")
#: The store's profile datasets the file is made from.
PROFILE_STORE_VARS = ("x_mean", "a", "a_stderr", "gap_mean", "contact_fraction")
#: netCDF compression of the profile variables.
ENCODING = {"zlib": True, "complevel": 4, "shuffle": True}


def profiles_dataset(rows: pd.DataFrame, data: dict[str, dict[str, np.ndarray]],
                     model_version: str, commits: list[str], campaign_hash: str = "",
                     parameters: tuple[str, ...] = PARAMETERS,
                     writer: str = "") -> xr.Dataset:
    """The profiles file's Dataset: one ``point`` per row of ``rows`` (a store's table,
    those with profiles, in order) from ``data`` (hash -> the store's profiles
    ``x_mean``, ``a``, ``a_stderr``, ``gap_mean``, ``contact_fraction``), with the swept
    ``parameters`` as coordinates along ``point``; ``writer`` says what wrote it."""
    from sweep.store.schema import column
    rows = rows[rows["hash"].isin(list(data))].reset_index(drop=True)
    n_floe = max((len(p["a"]) for p in data.values()), default=0)
    arrays = {k: np.full((len(rows), n_floe), np.nan, np.float32)
              for k in ("x", *PROFILE_FILE_VARS)}
    n_floes = np.zeros(len(rows), np.int32)
    for i, (h, a0) in enumerate(zip(rows["hash"], rows["a0"], strict=True)):
        p = data[h]
        n = len(p["a"])
        n_floes[i] = n
        arrays["x"][i, :n] = p["x_mean"]
        arrays["a_rel"][i, :n] = p["a"] / a0
        arrays["a_rel_stderr"][i, :n] = p["a_stderr"] / a0
        arrays["gap_mean"][i, :n] = p["gap_mean"]
        arrays["contact_fraction"][i, :n] = p["contact_fraction"]
    ds = xr.Dataset(
        {k: (("point", "floe"), arrays[k]) for k in PROFILE_FILE_VARS},
        coords={"floe": np.arange(n_floe, dtype=np.int32),
                "x": (("point", "floe"), arrays["x"]),
                "hash": ("point", rows["hash"].astype(str).to_numpy(object)),
                "status": ("point", rows["status"].astype(str).to_numpy(object)),
                **{p: ("point", rows[p].astype(str).to_numpy(object)
                       if not pd.api.types.is_numeric_dtype(rows[p])
                       else rows[p].to_numpy(float)) for p in parameters}})
    ds["n_floes"] = ("point", n_floes)
    for k, (units, long_name) in PROFILE_FILE_VARS.items():
        ds[k].attrs.update(units=units, long_name=long_name)
    ds["x"].attrs.update(units="m", long_name="time-mean floe centre from the ice edge")
    ds["floe"].attrs.update(units="1", long_name="floe index from the ice edge")
    ds["n_floes"].attrs.update(units="1", long_name="floes in the sheet (profile length)")
    ds["hash"].attrs.update(long_name="point identity: SHA-256 of its configuration,"
                            " the hash column of the table")
    ds["status"].attrs.update(long_name="point status (docs/output.md)")
    for p in parameters:
        col = column(p)
        ds[p].attrs.update(long_name=col.long_name, **({"units": col.units} if col.units
                                                        else {}))
    ds.attrs.update(
        parameters=" ".join(parameters),
        Conventions="CF-1.10",
        title="floewave: per-point profiles along the ice (a/a0, its standard error,"
              " mean gap, contact fraction)",
        source=f"floewave model version {model_version}",
        history=f"computed by sweep run at commit {', '.join(commits)}; written by"
                f" sweep export --profiles ({writer or 'floewave ' + floewave.__version__})",
        references="Herman, Cheng and Shen (2019), The Cryosphere 13, 2887,"
                   " doi:10.5194/tc-13-2887-2019",
        comment="floe positions are NaN beyond n_floes; the per-point scalars, config_json"
                " and provenance are in the campaign's table (sweep.load)",
        campaign_hash=str(campaign_hash),
    )
    return ds


def check_profiles_output(output: str | Path) -> None:
    """:class:`ConfigError` unless ``output`` is a ``.nc`` file name that can be written."""
    output = Path(output)
    if output.suffix != ".nc":
        raise ConfigError(f"--profiles {output}: expected a .nc file name")
    problem = output_file_problem(output, "--profiles")
    if problem:
        raise ConfigError(problem)


def load_profiles_file(path: str | Path, **selectors: Any) -> xr.Dataset:
    """The profiles of a ``.nc`` file :func:`export_profiles` wrote, or of every ``*.nc``
    file in a directory (its ``profiles/`` subdirectory when it has one; a campaign's
    shards, concatenated along ``point``), in memory. ``selectors`` keep the points with
    those parameter values (a value, or a list of values; floats to 1e-9 relative), e.g.
    ``load_profiles_file("results/herman2019", L_x=3.0, T=1.2, dispersion="ml")``.

    Raises :class:`PointNotFoundError` for a selector that is not a parameter or that no
    point matches, :class:`StoreError` for a path without profile files.
    """
    path = Path(path)
    if path.is_dir():
        folder = path / "profiles" if (path / "profiles").is_dir() else path
        files = sorted(folder.glob("*.nc"))
    else:
        files = [path]
    if not files or not all(p.is_file() for p in files):
        raise StoreError(f"{path}: no profiles file (.nc) there")
    parts = []
    for p in files:
        with xr.open_dataset(p, engine="h5netcdf") as ds:
            parts.append(ds.load())
    ds = parts[0] if len(parts) == 1 else xr.concat(parts, dim="point",
                                                    data_vars="minimal", coords="minimal",
                                                    compat="override", join="outer")
    hashes = ds["hash"].values.astype(str)
    if len(set(hashes)) != len(hashes):
        dup = pd.Series(hashes).value_counts()
        raise StoreError(f"{path}: point {dup.index[0][:12]} appears {int(dup.iloc[0])}"
                         " times across the profile files (two exports of one campaign in"
                         " one folder?)")
    along = [str(k) for k, v in ds.coords.items() if v.dims == ("point",)]
    keep = np.ones(ds.sizes["point"], bool)
    for name, want in selectors.items():
        if name not in along:
            raise PointNotFoundError(f"{path}: {name!r} is not a parameter of the profiles"
                                     f" (selectable: {', '.join(along)})",
                                     store=str(path), key=name)
        wanted = list(want) if isinstance(want, (list, tuple, np.ndarray)) else [want]
        col = ds[name].values
        hit = np.zeros(len(col), bool)
        numeric = np.issubdtype(col.dtype, np.number)
        for w in wanted:
            if name == "hash":
                hit |= np.array([str(c).startswith(str(w)) for c in col])
            elif numeric and not isinstance(w, str):
                hit |= np.isclose(col.astype(float), float(w), rtol=1e-9, atol=0.0)
            else:
                hit |= np.array([str(c) == str(w) for c in col])
        if name == "hash" and hit.sum() > len(wanted):
            raise PointNotFoundError(f"{path}: hash prefix {want!r} matches {int(hit.sum())}"
                                     " points", store=str(path), key=str(want))
        keep &= hit
    if not keep.any():
        raise PointNotFoundError(f"{path}: no point with profiles matches {selectors}",
                                 store=str(path), key=str(selectors))
    ds = ds.isel(point=np.flatnonzero(keep))
    ds.attrs["source_files"] = ", ".join(p.name for p in files)
    return ds
