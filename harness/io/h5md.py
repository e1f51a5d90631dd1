"""H5MD conformance of a state file (docs/interfaces.md, "HDF5 state"): what the H5MD 1.1
specification and its units module ask of the files the binaries write, checked element by
element, plus the strand structure this project documents (the per-particle `strand` id).

`problems(path)` lists every departure (empty when the file conforms); `units(path)` maps
each dataset that carries a `unit` attribute to its unit string."""

import re

import numpy as np

from harness import HarnessError
from harness.io.states import StateError

# The "SI" unit system of the units module: SI base and derived unit symbols, SI prefixes.
SI_UNITS = {"m", "g", "s", "A", "K", "mol", "cd", "rad", "sr", "Hz", "N", "Pa", "J", "W", "C", "V", "F"}
SI_UNITS |= {"ohm", "S", "Wb", "T", "H", "lm", "lx", "Bq", "Gy", "Sv", "kat"}
SI_PREFIXES = ("Y", "Z", "E", "P", "T", "G", "M", "k", "h", "da", "d", "c", "m", "u", "n", "p", "f", "a", "z", "y")
NUMBER = re.compile(r"[0-9]+(\.[0-9]+)?([+-][1-9][0-9]*)?")
FACTOR = re.compile(r"([A-Za-z]+)([+-][1-9][0-9]*)?")


def _is_si_symbol(symbol):
    return symbol in SI_UNITS or any(symbol.startswith(p) and symbol[len(p) :] in SI_UNITS for p in SI_PREFIXES)


def unit_string_problem(unit):
    """Why `unit` is not a unit string of the units module's grammar in the SI system, or None."""
    factors = unit.split(" ")
    if not unit or any(not f for f in factors):
        return "empty factor"
    seen = set()
    for k, factor in enumerate(factors):
        if NUMBER.fullmatch(factor):
            if k:
                return f"numeric factor '{factor}' is not the first"
            continue
        m = FACTOR.fullmatch(factor)
        if not m:
            return f"'{factor}' is neither a number nor a unit symbol with a signed power"
        if not _is_si_symbol(m.group(1)):
            return f"'{m.group(1)}' is not an SI unit symbol"
        if m.group(1) in seen:
            return f"'{m.group(1)}' occurs twice"
        seen.add(m.group(1))
    return None


def _fixed_ascii(attrs, name):
    """Whether attribute `name` is a fixed-length ASCII string (scalar or array)."""
    import h5py

    t = attrs.get_id(name).get_type()
    return isinstance(t, h5py.h5t.TypeStringID) and not t.is_variable_str() and t.get_cset() == h5py.h5t.CSET_ASCII


def _scalar(attrs, name):
    return attrs.get_id(name).get_space().get_simple_extent_ndims() == 0


def _text(value):
    return value.decode("ascii", "replace") if isinstance(value, bytes) else str(value)


def _check_string(where, attrs, name, out, required=True, shape=None):
    if name not in attrs:
        if required:
            out.append(f"{where}: no '{name}' attribute")
        return
    if not _fixed_ascii(attrs, name):
        out.append(f"{where}: '{name}' is not a fixed-length ASCII string")
    if shape is None and not _scalar(attrs, name):
        out.append(f"{where}: '{name}' is not scalar")
    if shape is not None and np.shape(attrs[name]) != shape:
        out.append(f"{where}: '{name}' has shape {np.shape(attrs[name])}, not {shape}")


def _check_version(where, attrs, out):
    v = attrs.get("version")
    if v is None or np.asarray(v).dtype.kind not in "iu" or np.shape(v) != (2,):
        out.append(f"{where}: 'version' is not Integer[2]")


def _walk(f):
    """Every dataset in the file, by path."""
    import h5py

    found = {}

    def visit(name, obj):  # h5py stops at the first visit that returns something
        if isinstance(obj, h5py.Dataset):
            found[name] = obj

    f.visititems(visit)
    return found


def _check_units(f, datasets, out):
    for name, d in datasets.items():
        if "unit" not in d.attrs:
            continue
        _check_string(f"/{name}", d.attrs, "unit", out)
        why = unit_string_problem(_text(d.attrs["unit"]))
        if why:
            out.append(f"/{name}: unit '{_text(d.attrs['unit'])}': {why}")


def _elements(f, root):
    """The time-dependent H5MD elements (groups holding value, step and time) under root."""
    import h5py

    if root not in f:
        return {}
    found = {}

    def visit(name, obj):
        if isinstance(obj, h5py.Group) and {"value", "step", "time"} <= set(obj):
            found[f"{root}/{name}"] = obj

    f[root].visititems(visit)
    return found


def _check_element(name, g, out, value_unit):
    value, step, time = g["value"], g["step"], g["time"]
    if step.dtype.kind not in "iu" or step.ndim != 1:
        out.append(f"/{name}/step is not Integer[variable]")
    if time.dtype.kind != "f" or time.ndim != 1:
        out.append(f"/{name}/time is not Float[variable]")
    if not (len(step) == len(time) == value.shape[0]):
        out.append(f"/{name}: step, time and value have {len(step)}, {len(time)}, {value.shape[0]} entries")
    if "unit" not in time.attrs or _text(time.attrs["unit"]) != "s":
        out.append(f"/{name}/time has no unit 's'")
    if value_unit and "unit" not in value.attrs:
        out.append(f"/{name}/value has no unit")


def _check_strands(f, out):
    hair = f["particles/hair"]
    if "strand" not in hair:
        out.append("/particles/hair has no per-particle 'strand' dataset")
        return
    try:
        n, p = int(f["parameters"].attrs["n_strands"]), int(f["parameters"].attrs["points_per_strand"])
    except KeyError:
        out.append("/parameters has no n_strands or points_per_strand")
        return
    if not np.array_equal(hair["strand"][()], np.repeat(np.arange(n), p)):
        out.append("/particles/hair/strand is not the strand index of each particle (row i*P + k holds i)")


def problems(path):
    """Every departure of the state at `path` from H5MD 1.1 and its units module, and from
    the documented strand structure; an empty list when the file conforms."""
    from harness.core import inputs

    try:
        f = inputs.open_h5(path, "state")
    except HarnessError as e:
        raise StateError(str(e)) from None
    out = []
    with f:
        if "h5md" not in f:
            return [f"{path}: no /h5md group"]
        h5md = f["h5md"]
        _check_version("/h5md", h5md.attrs, out)
        for group, names in (("author", ("name",)), ("creator", ("name", "version"))):
            if group not in h5md:
                out.append(f"/h5md: no '{group}' group")
                continue
            for name in names:
                _check_string(f"/h5md/{group}", h5md[group].attrs, name, out)
            _check_string(f"/h5md/{group}", h5md[group].attrs, "email", out, required=False)
        datasets = _walk(f)
        if any("unit" in d.attrs for d in datasets.values()):
            if "modules/units" not in h5md:
                out.append("/h5md/modules/units is missing but datasets carry units")
            else:
                units_group = h5md["modules/units"]
                _check_version("/h5md/modules/units", units_group.attrs, out)
                _check_string("/h5md/modules/units", units_group.attrs, "system", out)
                if "system" in units_group.attrs and _text(units_group.attrs["system"]) != "SI":
                    out.append("/h5md/modules/units: system is not 'SI'")
        _check_units(f, datasets, out)
        for name, group in f.get("particles", {}).items():
            box = group.get("box")
            if box is None:
                out.append(f"/particles/{name}: no box")
                continue
            dim = box.attrs.get("dimension")
            if dim is None or np.shape(dim) != () or np.asarray(dim).dtype.kind not in "iu":
                out.append(f"/particles/{name}/box: 'dimension' is not a scalar Integer")
                continue
            _check_string(f"/particles/{name}/box", box.attrs, "boundary", out, shape=(int(dim),))
            if "boundary" in box.attrs and not {_text(b) for b in box.attrs["boundary"]} <= {"none", "periodic"}:
                out.append(f"/particles/{name}/box: boundary is not 'none' or 'periodic'")
        for name, g in _elements(f, "particles").items():
            _check_element(name, g, out, value_unit=name.rsplit("/", 1)[-1] in ("position", "velocity"))
        for name, g in _elements(f, "observables").items():
            _check_element(name, g, out, value_unit=False)  # dimensionless observables carry none
        if "particles/hair/rest_position" in f and "unit" not in f["particles/hair/rest_position"].attrs:
            out.append("/particles/hair/rest_position has no unit")
        if "particles/hair" in f:
            _check_strands(f, out)
    return out


def units(path):
    """{dataset path: unit string} for every dataset of the state that carries a `unit`."""
    import h5py

    with h5py.File(path, "r") as f:
        return {name: _text(d.attrs["unit"]) for name, d in _walk(f).items() if "unit" in d.attrs}
