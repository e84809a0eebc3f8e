#!/usr/bin/env python3
# SPDX-License-Identifier: MIT
"""Fails if a library source includes a header it may not see (docs/developing.md, "Layout").

Each library may include its own headers and the public headers of the libraries below it;
data flows one way (core -> eos -> continuum, particles -> coupling -> app). In particular the
coupled problem (coupling/) sees the grid only through cont.h and the particles only through
the particle-region interface ptl_region.h (and the particle state ptl.h it is built on).
Tests, benchmarks and fuzzers may look inside (white-box tests); they are not checked.
Usage: tests/include_check.py SOURCE_DIR
"""
import pathlib
import re
import sys

# library: (folder, its public headers, the libraries it may use)
LIBS = {
    "core": ("core", {"core.h"}, []),
    "eos": ("eos", {"eos.h"}, ["core"]),
    "continuum": ("continuum", {"cont.h", "cont2d.h"}, ["core", "eos"]),
    "ptl": ("particles", {"ptl.h", "ptl_region.h"}, ["core", "eos"]),
    "cd": ("particles/cd", {"cd.h"}, ["core", "eos", "ptl", "ptl_impl"]),
    "dm": ("particles/dm", {"dm.h"}, ["core", "eos", "ptl", "ptl_impl"]),
    "coupling": ("coupling", {"cpl.h"}, ["core", "eos", "continuum", "ptl"]),
    "app": ("app", {"commands.h"}, ["core", "eos", "continuum", "ptl", "cd", "dm", "coupling"]),
}
# The implementations of ptl_region.h see its table of functions; regions.c names them.
EXTRA = {"ptl_impl": {"ptl_region_impl.h"}}
FILE_LIBS = {"particles/regions.c": ["core", "eos", "ptl", "cd", "dm"]}
# Headers the build generates (cmake/GitVersion.cmake, the configured build facts): the app's.
GENERATED = {"mscale_build_config.h": "app", "mscale_git.h": "app"}

root = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else ".")
own = {}  # header name -> library
for lib, (folder, _, _) in LIBS.items():
    for h in (root / folder).glob("*.h"):
        own[h.name] = lib
own.update(GENERATED)
for lib, hs in EXTRA.items():
    for h in hs:
        own[h] = lib
public = {lib: pub for lib, (_, pub, _) in LIBS.items()}
public.update(EXTRA)

bad = []
for lib, (folder, _, deps) in LIBS.items():
    for f in sorted((root / folder).glob("*.[ch]")):
        rel = f.relative_to(root).as_posix()
        allowed = set(FILE_LIBS.get(rel, deps))
        for n, line in enumerate(f.read_text(errors="replace").splitlines(), 1):
            m = re.match(r'\s*#\s*include\s+"([^"]+)"', line)
            if not m:
                continue
            h = pathlib.PurePosixPath(m.group(1)).name
            owner = own.get(h)
            if owner is None:
                bad.append(f"{rel}:{n}: includes \"{h}\", which no library owns")
            elif owner == lib or (owner == "ptl_impl" and lib == "ptl"):
                continue
            elif owner not in allowed:
                bad.append(f"{rel}:{n}: {lib} may not use {owner} (\"{h}\")")
            elif h not in public[owner]:
                bad.append(f"{rel}:{n}: \"{h}\" is private to {owner}")
if bad:
    print("include_check: includes across the layering (docs/developing.md, \"Layout\"):")
    print("\n".join(bad))
    sys.exit(1)
print(f"include_check: every library includes only what it may see ({len(LIBS)} libraries)")
