#!/usr/bin/python3
"""No upward include: every file of src/LAYER/ and every public header includes only from its own
layer and the layers below it (issue 17). The layers, lowest first, are LAYERS; a public header
include/accelcal/NAME.hpp belongs to the layer of src/LAYER/NAME.cpp, or to PUBLIC_ONLY's entry
when it has no source file. A file in an unknown folder of src/, or a public header of no known
layer, is an error too, so the rule cannot be bypassed by adding one.

  check_layers.py SOURCE_DIR
"""
import os
import re
import sys

LAYERS = ["core", "model", "io", "solvers", "statistics", "analysis", "platform", "output",
          "pipeline"]
PUBLIC_ONLY = {"types.hpp": "core", "names.hpp": "core"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def main():
    root = sys.argv[1]
    src, public = os.path.join(root, "src"), os.path.join(root, "include", "accelcal")
    errors = []
    layer_of_file = {}  # path relative to root -> layer
    for dirpath, _, files in os.walk(src):
        rel = os.path.relpath(dirpath, src)
        for name in files:
            path = os.path.join("src", rel, name) if rel != "." else os.path.join("src", name)
            layer = rel.split(os.sep)[0]
            if layer not in LAYERS:
                errors.append(f"{path}: not in a layer folder ({', '.join(LAYERS)})")
                continue
            layer_of_file[path] = layer
    public_layer = dict(PUBLIC_ONLY)
    for path, layer in layer_of_file.items():
        base = os.path.splitext(os.path.basename(path))[0] + ".hpp"
        if path.endswith(".cpp") and os.path.exists(os.path.join(public, base)):
            if public_layer.get(base, layer) != layer:
                errors.append(f"include/accelcal/{base}: implemented in two layers")
            public_layer[base] = layer
    for name in sorted(os.listdir(public)):
        if name not in public_layer:
            errors.append(f"include/accelcal/{name}: no src/LAYER/{name[:-4]}.cpp and not in "
                          "PUBLIC_ONLY: its layer is unknown")
            continue
        layer_of_file[os.path.join("include", "accelcal", name)] = public_layer[name]
    for path, layer in sorted(layer_of_file.items()):
        with open(os.path.join(root, path), encoding="utf-8") as f:
            text = f.read()
        for included in INCLUDE.findall(text):
            if included.startswith("accelcal/"):
                target = public_layer.get(included[len("accelcal/"):])
            else:
                target = included.split("/")[0] if "/" in included else None
            if target is None or target not in LAYERS:
                errors.append(f"{path}: includes \"{included}\", which is in no layer")
            elif LAYERS.index(target) > LAYERS.index(layer):
                errors.append(f"{path} ({layer}) includes \"{included}\" ({target}): upward")
    for e in errors:
        print(e)
    if errors:
        sys.exit(1)
    print(f"{len(layer_of_file)} files, no upward include")


if __name__ == "__main__":
    main()
