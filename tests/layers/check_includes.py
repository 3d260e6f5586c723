#!/usr/bin/python3
"""Every quoted #include in deli's sources resolves to a header of the file's own layer or
of a layer below it. Layers, lowest first: engine, forcefields, io, crosscheck (io/crosscheck),
app. A header is looked up as the compiler does: next to the including file, then under each
layer's include root. Usage: check_includes.py SOURCE_DIR; exit status 1 on a violation."""
import pathlib
import re
import sys

LAYERS = ["engine", "forcefields", "io", "crosscheck", "app"]
ROOTS = {"engine": "engine", "forcefields": "forcefields", "io": "io", "app": "app"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"')


def layer_of(path, top):
    rel = path.relative_to(top).parts
    if rel[0] == "io" and len(rel) > 1 and rel[1] == "crosscheck":
        return "crosscheck"
    return rel[0] if rel[0] in LAYERS else None


def main():
    top = pathlib.Path(sys.argv[1]).resolve()
    violations = []
    checked = 0
    for layer in ROOTS.values():
        for source in sorted((top / layer).rglob("*")):
            if source.suffix not in (".cpp", ".hpp", ".h"):
                continue
            own = layer_of(source, top)
            for number, line in enumerate(source.read_text().splitlines(), 1):
                match = INCLUDE.match(line)
                if not match:
                    continue
                name = match.group(1)
                candidates = [source.parent / name] + [top / root / name for root in ROOTS.values()]
                found = next((c.resolve() for c in candidates if c.is_file()), None)
                if found is None:
                    continue  # a generated or external header
                checked += 1
                target = layer_of(found, top)
                if target and LAYERS.index(target) > LAYERS.index(own):
                    violations.append(f"{source.relative_to(top)}:{number}: the {own} layer "
                                      f"includes \"{name}\" of the {target} layer above it")
    for v in violations:
        print(v)
    print(f"{checked} includes checked, {len(violations)} upward")
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main())
