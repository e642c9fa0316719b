"""What ``tactilevision cache`` does once its options are parsed
(:mod:`tactilevision.cli._cache`): what the disk cache holds, and emptying it.

Imported only when the command runs, so that its ``--help`` does not load this stack.
"""

from __future__ import annotations

import argparse
import json

from .. import cache_info, cache_limit_bytes, cache_root, clear_cache
from ..io import write_output_file

__all__ = ["run_clear", "run_info"]


def run_info(args: argparse.Namespace) -> int:
    """Print (or write as JSON) the cache's folders, files and bytes, and its bound."""
    info = cache_info()
    doc = {"root": str(cache_root()), "limit_mb": cache_limit_bytes() / 2**20,
           "folders": {k: {"files": n, "mb": b / 2**20} for k, (n, b) in info.items()},
           # the suite's own renders (tests/) are not counted against the bound
           "bounded_mb": sum(b for k, (_, b) in info.items() if k != "tests") / 2**20}
    if args.json == "-":
        print(json.dumps(doc, indent=2))
        return 0
    print(f"cache {doc['root']}: {doc['bounded_mb']:.1f} MiB of at most "
          f"{doc['limit_mb']:.0f} MiB ($TACTILEVISION_CACHE_MB; tests not counted)")
    for name, d in doc["folders"].items():
        print(f"  {name:8s} {d['files']:6d} files {d['mb']:9.1f} MiB")
    if args.json:
        write_output_file(args.json, json.dumps(doc, indent=2) + "\n", overwrite=True)
    return 0


def run_clear(args: argparse.Namespace) -> int:
    """Delete the cache's files (one folder, or all)."""
    files, size = clear_cache(args.folder)
    where = cache_root() if args.folder is None else cache_root() / args.folder
    print(f"removed {files} files ({size / 2**20:.1f} MiB) from {where}")
    return 0
