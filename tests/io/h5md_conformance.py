#!/usr/bin/python3
"""Checks an H5MD file against the structure the H5MD 1.1 specification requires
(https://www.nongnu.org/h5md/h5md.html), walking the file with h5py, and then what deli
promises beyond it.

usage: h5md_conformance.py [--deli] FILE.h5

The specification's requirements checked:
- /h5md: `version` Integer[2] = [1, 1]; `author` group with `name`; `creator` group with
  `name` and `version` (fixed-length strings of scalar dataspace); modules with `version`.
- every time-dependent element (a group holding `value`): `step` Integer[variable] and
  monotonically increasing (or a scalar step, the fixed mode, with an Integer `offset`),
  `time` optional, Float or Integer, same length as `step`; `value`'s first dimension
  equals `step`'s.
- /particles/<group>: a `box` group with `dimension` (Integer, scalar) and `boundary`
  (fixed-length strings, [D], "periodic" or "none"); `edges` (unless every boundary is
  none) a [D] vector or [D][D] matrix, time-dependent or not; a time-dependent box's step
  and time are hard links to the position's, as are the image's; `position`, `velocity`,
  `force`, `image` of shape [variable][N][D]; `mass` Float, `species` Integer or
  Enumeration, `id` Integer and unique, `charge` Integer or Float, all of N particles.
- /observables: elements (datasets, or time-dependent groups) and subgroups of them.
- /connectivity: Integer tuples [N][T] (or a time-dependent group of them) with a
  `particles_group` object reference to a group of /particles; the values are that
  group's `id` values when it has `id`, else indices into it.
- units (the units module): a `unit` attribute is a fixed-length string.

With --deli, also deli's own promises: /particles/all; every series of /particles/all and
/observables sampled at the position's steps shares the position's step and time datasets
(hard links, not copies); `diameter`, where present, positive of shape [N]; /parameters.
Exit 1 naming every violation.
"""
import sys

import h5py
import numpy as np

failures = []


def fail(message):
    failures.append(message)


def is_int(dtype):
    return dtype.kind in "iu"


def is_float_or_int(dtype):
    return dtype.kind in "iuf"


def fixed_string_attribute(obj, name, where):
    if name not in obj.attrs:
        fail(f"{where}: missing attribute {name}")
        return None
    attr = obj.attrs.get_id(name)
    kind = attr.get_type()
    if not isinstance(kind, h5py.h5t.TypeStringID) or kind.is_variable_str():
        fail(f"{where}/{name}: not a fixed-length string")
    if attr.shape != ():
        fail(f"{where}/{name}: dataspace {attr.shape}, the specification asks for a scalar")
    value = obj.attrs[name]
    return value.decode() if isinstance(value, bytes) else str(value)


def same_object(a, b):
    return h5py.h5o.get_info(a.id).addr == h5py.h5o.get_info(b.id).addr


def time_dependent(group, where):
    """Checks a time-dependent element; returns the number of samples (None if malformed)."""
    if "step" not in group or "value" not in group:
        fail(f"{where}: a time-dependent element needs step and value")
        return None
    step, value = group["step"], group["value"]
    if not is_int(step.dtype):
        fail(f"{where}/step: type {step.dtype}, not Integer")
    if value.ndim < 1:
        fail(f"{where}/value: a scalar dataspace; its first dimension counts the samples")
        return None
    if step.shape == ():  # fixed step and time storage
        if "offset" in step.attrs and not is_int(np.asarray(step.attrs["offset"]).dtype):
            fail(f"{where}/step: offset is not Integer")
        if "time" in group and group["time"].shape != ():
            fail(f"{where}/time: must be scalar when step is")
        return value.shape[0]
    if step.ndim != 1:
        fail(f"{where}/step: shape {step.shape}, not [variable]")
        return None
    steps = step[()]
    if np.any(np.diff(steps) <= 0):
        fail(f"{where}/step: not monotonically increasing")
    if value.shape[0] != steps.shape[0]:
        fail(f"{where}: value holds {value.shape[0]} samples, step {steps.shape[0]}")
    if "time" in group:
        time = group["time"]
        if not is_float_or_int(time.dtype):
            fail(f"{where}/time: type {time.dtype}, neither Float nor Integer")
        if time.shape != step.shape:
            fail(f"{where}/time: shape {time.shape}, step's {step.shape}")
        elif np.any(np.diff(time[()]) <= 0):
            fail(f"{where}/time: not monotonically increasing")
    return value.shape[0]


def element_data(obj, where):
    """An element's data: (dataset of the samples or the values, time-dependent?)."""
    if isinstance(obj, h5py.Group):
        if time_dependent(obj, where) is None:
            return None, True
        return obj["value"], True
    return obj, False


def check_metadata(f):
    if "h5md" not in f or not isinstance(f["h5md"], h5py.Group):
        fail("missing the /h5md group (the only mandatory one)")
        return
    h5md = f["h5md"]
    version = h5md.attrs.get("version")
    if version is None:
        fail("/h5md: missing attribute version")
    else:
        version = np.asarray(version)
        if not is_int(version.dtype) or version.shape != (2,):
            fail(f"/h5md/version: {version.dtype}{list(version.shape)}, not Integer[2]")
        elif list(version) != [1, 1]:
            fail(f"/h5md/version: {list(version)}, not [1, 1]")
    for name, attrs in (("author", ["name"]), ("creator", ["name", "version"])):
        if name not in h5md or not isinstance(h5md[name], h5py.Group):
            fail(f"/h5md: missing the {name} group")
            continue
        for attr in attrs:
            fixed_string_attribute(h5md[name], attr, f"/h5md/{name}")
        if "email" in h5md[name].attrs:
            email = fixed_string_attribute(h5md[name], "email", f"/h5md/{name}")
            if email is not None and "@" not in email:
                fail(f"/h5md/{name}/email: {email!r} is not of the form email@domain.tld")
    if "modules" in h5md:
        for module_name, module in h5md["modules"].items():
            v = np.asarray(module.attrs.get("version", []))
            if not is_int(v.dtype) or v.shape != (2,):
                fail(f"/h5md/modules/{module_name}: version is not Integer[2]")


def check_particles_group(group, where):
    """Returns the number of particles (None when no element fixes it)."""
    counts = {}
    position = group.get("position")
    if "box" not in group or not isinstance(group["box"], h5py.Group):
        fail(f"{where}: missing the box group")
        dimension = 3
    else:
        box = group["box"]
        dimension = np.asarray(box.attrs.get("dimension", -1))
        if "dimension" not in box.attrs:
            fail(f"{where}/box: missing attribute dimension")
        elif not is_int(dimension.dtype) or dimension.shape != ():
            fail(f"{where}/box/dimension: {dimension.dtype}{list(dimension.shape)}, not "
                 "an Integer scalar")
        dimension = int(dimension) if "dimension" in box.attrs else 3
        boundary = None
        if "boundary" not in box.attrs:
            fail(f"{where}/box: missing attribute boundary")
        else:
            kind = box.attrs.get_id("boundary").get_type()
            if not isinstance(kind, h5py.h5t.TypeStringID) or kind.is_variable_str():
                fail(f"{where}/box/boundary: not fixed-length strings")
            boundary = [b.decode() if isinstance(b, bytes) else str(b)
                        for b in np.atleast_1d(box.attrs["boundary"])]
            if len(boundary) != dimension:
                fail(f"{where}/box/boundary: {len(boundary)} entries, dimension {dimension}")
            if any(b not in ("periodic", "none") for b in boundary):
                fail(f"{where}/box/boundary: {boundary}, not periodic or none")
        if "edges" not in box:
            if boundary is None or any(b != "none" for b in boundary):
                fail(f"{where}/box: no edges, and not every boundary is none")
        else:
            edges, timed = element_data(box["edges"], f"{where}/box/edges")
            if edges is not None:
                shape = edges.shape[1:] if timed else edges.shape
                if shape not in ((dimension,), (dimension, dimension)):
                    fail(f"{where}/box/edges: data of shape {shape}, neither [D] nor [D][D]")
                if not is_float_or_int(edges.dtype):
                    fail(f"{where}/box/edges: type {edges.dtype}")
            if timed:
                if not isinstance(position, h5py.Group):
                    fail(f"{where}/box/edges: time-dependent without a time-dependent position")
                else:
                    for link in ("step", "time"):
                        if (link in position) != (link in box["edges"]) or (
                                link in position
                                and not same_object(position[link], box["edges"][link])):
                            fail(f"{where}/box/edges/{link}: not a hard link to position's "
                                 f"{link} (required)")
    for name in ("position", "velocity", "force", "image"):
        if name not in group:
            continue
        data, timed = element_data(group[name], f"{where}/{name}")
        if data is None:
            continue
        shape = data.shape[1:] if timed else data.shape
        if len(shape) != 2 or shape[1] != dimension:
            fail(f"{where}/{name}: data of shape {shape}, not [N][{dimension}]")
        else:
            counts[name] = shape[0]
        if not is_float_or_int(data.dtype):
            fail(f"{where}/{name}: type {data.dtype}, neither Float nor Integer")
    if "image" in group:
        if position is None:
            fail(f"{where}/image: present without position")
        elif isinstance(group["image"], h5py.Group):
            for link in ("step", "time"):
                if (link in position) != (link in group["image"]) or (
                        link in position
                        and not same_object(position[link], group["image"][link])):
                    fail(f"{where}/image/{link}: not a hard link to position's {link} "
                         "(required)")
    scalar_types = {"mass": ("f", "Float"), "species": ("iu", "Integer or Enumeration"),
                    "id": ("iu", "Integer"), "charge": ("iuf", "Integer or Float")}
    for name, (kinds, words) in scalar_types.items():
        if name not in group:
            continue
        data, timed = element_data(group[name], f"{where}/{name}")
        if data is None:
            continue
        enumeration = h5py.check_enum_dtype(data.dtype) is not None
        if data.dtype.kind not in kinds and not (name == "species" and enumeration):
            fail(f"{where}/{name}: type {data.dtype}, not {words}")
        shape = data.shape[1:] if timed else data.shape
        if len(shape) != 1:
            fail(f"{where}/{name}: data of shape {shape}, not [N]")
        else:
            counts[name] = shape[0]
        if name == "id":
            ids = data[()]
            for frame in (ids if timed else [ids]):
                if len(np.unique(frame)) != len(frame):
                    fail(f"{where}/id: identifiers not unique")
    if len(set(counts.values())) > 1:
        fail(f"{where}: elements disagree on the particle count: {counts}")
    return next(iter(counts.values()), None)


def check_observables(group, where):
    for name, obj in group.items():
        path = f"{where}/{name}"
        if isinstance(obj, h5py.Group) and "value" not in obj:
            check_observables(obj, path)  # a subgroup of observables
        else:
            element_data(obj, path)


def check_connectivity(f, group, where):
    for name, obj in group.items():
        path = f"{where}/{name}"
        if isinstance(obj, h5py.Group) and "value" not in obj:
            check_connectivity(f, obj, path)
            continue
        data, timed = element_data(obj, path)
        if data is None:
            continue
        if not is_int(data.dtype):
            fail(f"{path}: type {data.dtype}, not Integer")
        reference = obj.attrs.get("particles_group")
        if reference is None or not isinstance(reference, h5py.Reference):
            fail(f"{path}: no particles_group object reference")
            continue
        target = f[reference]
        if not isinstance(target, h5py.Group) or not target.name.startswith("/particles/"):
            fail(f"{path}: particles_group refers to {target.name}, not a group of /particles")
            continue
        tuples = data[()]
        if tuples.ndim != (3 if timed else 2) and tuples.ndim != (2 if timed else 1):
            fail(f"{path}: shape {tuples.shape}, not [N][T] (or a list [N])")
        values = tuples.ravel()
        if "id" in target:
            ids, id_timed = element_data(target["id"], f"{target.name}/id")
            known = set(np.asarray(ids[()]).ravel().tolist())
            unknown = sorted(set(values.tolist()) - known)
            if unknown:
                fail(f"{path}: values {unknown[:5]} are not particle ids of {target.name} "
                     "(it has an id element, so the tuples hold ids)")
        else:
            n = check_particles_group(target, target.name)
            if n is not None and (values.min(initial=0) < 0 or values.max(initial=0) >= n):
                fail(f"{path}: indices outside [0, {n}) of {target.name}")


def check_units(f):
    def visit(name, obj):
        if "unit" in obj.attrs:
            kind = obj.attrs.get_id("unit").get_type()
            if not isinstance(kind, h5py.h5t.TypeStringID):
                fail(f"/{name}: unit attribute is not a string")
    f.visititems(visit)


def check_deli(f):
    if "particles/all" not in f:
        fail("deli: no /particles/all")
        return
    if "parameters" not in f:
        fail("deli: no /parameters (the input)")
    all_ = f["particles/all"]
    position = all_.get("position")
    if not isinstance(position, h5py.Group):
        fail("deli: /particles/all/position is not a time series")
        return
    steps = position["step"][()]
    shared = 0
    series = [(f"/particles/all/{n}", all_[n]) for n in ("velocity", "force", "image")
              if n in all_]
    series.append(("/particles/all/box/edges", all_["box/edges"]))
    for name, obj in f.get("observables", {}).items():
        if isinstance(obj, h5py.Group) and "step" in obj:
            series.append((f"/observables/{name}", obj))
    for path, obj in series:
        if np.array_equal(obj["step"][()], steps):
            for link in ("step", "time"):
                if not same_object(obj[link], position[link]):
                    fail(f"deli: {path}/{link} is sampled with the position but is a copy, "
                         "not a hard link")
            shared += 1
    if "diameter" in all_:
        d = all_["diameter"]
        if d.shape != (position["value"].shape[1],) or d.dtype.kind != "f" or np.any(
                d[()] <= 0):
            fail(f"deli: /particles/all/diameter {d.dtype}{d.shape} is not positive Float[N]")
    return shared


def main():
    paths = [a for a in sys.argv[1:] if a != "--deli"]
    deli = "--deli" in sys.argv[1:]
    if len(paths) != 1:
        sys.exit(__doc__)
    path = paths[0]
    with h5py.File(path, "r") as f:
        check_metadata(f)
        groups = 0
        for name, group in f.get("particles", {}).items():
            check_particles_group(group, f"/particles/{name}")
            groups += 1
        if "observables" in f:
            check_observables(f["observables"], "/observables")
        if "connectivity" in f:
            check_connectivity(f, f["connectivity"], "/connectivity")
        check_units(f)
        shared = check_deli(f) if deli else None
        for failure in failures:
            print("FAIL:", failure)
        summary = (f"{path}: {groups} particle group(s), "
                   f"{len(f.get('observables', {}))} observables, "
                   f"{len(f.get('connectivity', {}))} connectivity lists")
        if shared is not None:
            summary += f", {shared} series sharing the position's step and time"
        print(summary + (": H5MD 1.1 conformant" if not failures
                         else f": {len(failures)} violations"))
    sys.exit(1 if failures else 0)


main()
