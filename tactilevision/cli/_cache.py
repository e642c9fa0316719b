"""``tactilevision cache info|clear``: what the disk cache holds, and emptying it."""

from __future__ import annotations

import argparse
import importlib

__all__ = ["add_parser", "run_clear", "run_info"]


def add_parser(sub: argparse._SubParsersAction) -> None:
    """Register ``cache`` and its ``info`` and ``clear`` sub-commands."""
    p = sub.add_parser("cache", help="what the disk cache holds (info), or empty it (clear)",
                       description="The disk cache ($TACTILEVISION_CACHE, else "
                       "~/.cache/tactilevision): FEM sweeps and stiffness, optics tables. "
                       "Bounded by $TACTILEVISION_CACHE_MB MiB (least recently used files go "
                       "first); deleting it is always safe.")
    csub = p.add_subparsers(dest="cache_command", metavar="SUBCOMMAND", required=True)
    i = csub.add_parser("info", help="files and size per folder, and the bound")
    i.add_argument("--json", metavar="FILE", help="write the figures as JSON ('-': stdout)")
    i.set_defaults(func=run_info)
    c = csub.add_parser("clear", help="delete the cache's files (they are computed again)")
    c.add_argument("--folder", choices=("fem", "optics", "tests"), default=None,
                   help="one folder only (default: all)")
    c.set_defaults(func=run_clear)


def run_info(args: argparse.Namespace) -> int:
    """Run ``cache info``: :func:`~tactilevision.cli._cache_run.run_info`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._cache_run", __package__).run_info(args)


def run_clear(args: argparse.Namespace) -> int:
    """Run ``cache clear``: :func:`~tactilevision.cli._cache_run.run_clear`, imported only now
    (``--help`` reads the options without the command's stack)."""
    return importlib.import_module("._cache_run", __package__).run_clear(args)
