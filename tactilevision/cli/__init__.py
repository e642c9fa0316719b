"""The ``tactilevision`` command line.

Each sub-command lives in its own module with ``add_parser(subparsers)`` and
``run(args) -> int``. That module imports only the standard library and the package
root (no NumPy), so that any command's ``--help`` is quick; its ``run`` imports the
command's work from ``_<name>_run`` when the command runs (tests/test_cli_help_imports.py
keeps it so). Bad input raises :class:`tactilevision.InputError`; the
command prints its one-sentence message on standard error and exits with
status 2, deleting nothing already written (``docs/formats.md``).
"""

from __future__ import annotations

import argparse
import gc
import importlib
import os
import signal
import sys
import threading
import warnings
from collections.abc import Sequence

from .. import InputError, InputWarning, __version__

__all__ = ["COMMANDS", "EXTRAS", "build_parser", "main", "missing_extra", "synopses"]

#: Each command, its module (imported only when the command runs or shows its help, so
#: that ``--version`` and ``--help`` do not load every command's parser; light itself, its
#: work in ``<module>_run``) and its one-line help (a test keeps it equal to the module's
#: own).
COMMANDS: dict[str, tuple[str, str]] = {
    "calibrate": ("_calibrate", "session of frames and forces -> certified presses, E, nu, "
                                "report"),
    "reconstruct": ("_reconstruct", "height maps (.npy, mm) and heights.csv from a folder of "
                                    "frames or a video (depth images with --images)"),
    "optics": ("_optics", "photometric calibration of a sensor"),
    "fit": ("_fit", "fit E and nu to a measurements table"),
    "diagnose": ("_diagnose", "find where the model fails and which effect is missing"),
    "validate": ("_validate", "simulated against measured depths (FEM check)"),
    "plan": ("_plan", "predict what a calibration session's design will measure"),
    "fem": ("_fem", "finite-element tables of the gel layer"),
    "forces": ("_forces", "contact pressure maps (.npy, kPa) and total forces per frame "
                          "(forces.csv; images with --images)"),
    "history": ("_history", "calibration folders over days -> each gel's E and nu history, "
                            "trend, recalibrate or not"),
    "batch": ("_batch", "reconstruct / forces / calibrate over many inputs on Dask (Zarr, "
                        "Parquet)"),
    "live": ("_live", "a camera, video or frame folder through the live pipeline: annotated "
                      "video, CSV"),
    "view": ("_view", "an interactive, self-contained HTML viewer (frame, height map, 3D "
                      "surface, force map, frame slider)"),
    "cache": ("_cache", "what the disk cache holds (info), or empty it (clear)"),
}


def _module(name: str):
    """A command's module, imported on use (the command line's lazy dispatch)."""
    return importlib.import_module(f"{__name__}.{COMMANDS[name][0]}")


def build_parser(commands: Sequence[str] | None = None) -> argparse.ArgumentParser:
    """Build the argument parser.

    Parameters
    ----------
    commands : sequence of str, optional
        The commands whose full parsers are built (their modules imported); the others
        are listed by name and help alone. Default: every command.

    Returns
    -------
    parser : argparse.ArgumentParser
    """
    parser = argparse.ArgumentParser(
        prog="tactilevision",
        description="Vision-based tactile sensors: height maps by photometric stereo, "
        "in-situ elastomer calibration (E, nu), contact forces.",
    )
    parser.add_argument("--version", action="version", version=f"tactilevision {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)
    full = set(COMMANDS if commands is None else commands)
    for name, (_, help_text) in COMMANDS.items():
        if name in full:
            _module(name).add_parser(sub)
        else:
            sub.add_parser(name, help=help_text, add_help=False)
    return parser


def synopses() -> list[str]:
    """One usage line per command, generated from the parsers (``docs/guide/cli.md``
    shows exactly these; a test keeps the page equal to them).

    Returns
    -------
    list of str
        ``tactilevision COMMAND [SUBCOMMAND] ...`` with every option, in the order
        the commands are registered.
    """
    out = []

    def walk(parser: argparse.ArgumentParser) -> None:
        subs = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        if subs:
            for child in subs[0].choices.values():
                walk(child)
            return
        fmt = argparse.HelpFormatter(parser.prog, width=100_000)
        fmt.add_usage(parser.usage, parser._actions, parser._mutually_exclusive_groups,
                      prefix="")
        out.append(fmt.format_help().strip().replace(" [-h]", "", 1))

    for action in build_parser()._actions:
        if isinstance(action, argparse._SubParsersAction):
            for child in action.choices.values():
                walk(child)
    return out


def main(argv: Sequence[str] | None = None) -> int:
    """Run the command line; return the exit status.

    Parameters
    ----------
    argv : sequence of str, optional
        Arguments without the program name; ``sys.argv[1:]`` when None.

    Returns
    -------
    status : int
        0 on success, 2 on bad input (message on standard error), 130 when
        interrupted (Ctrl-C: one line, no traceback).

    Notes
    -----
    A Ctrl-C ends the process: should the command not have returned within
    :data:`INTERRUPT_GRACE_S` of it, a watchdog exits with status 130 (so a program that
    calls ``main`` in-process is ended too).
    """
    argv = list(sys.argv[1:] if argv is None else argv)
    # only the command that runs is imported: --version and --help stay light
    first = next((a for a in argv if not a.startswith("-")), None)
    name = first if first in COMMANDS else ""
    with _interrupts(name):               # from the first moment: its imports included
        try:
            parser = build_parser([first] if first in COMMANDS else [])
            args = parser.parse_args(argv)
        except KeyboardInterrupt:
            print(f"\ntactilevision {name}: interrupted", file=sys.stderr)
            status = 130
        else:
            args.argv = argv
            status = _run(args)
    if status == 130:
        _forget_caught_interrupt()
    return status


def _forget_caught_interrupt() -> None:
    """Clear CPython's record of a KeyboardInterrupt that escaped an ``exec`` or ``eval``
    of source text, once the command has caught the interrupt itself.

    CPython (3.11) notes a KeyboardInterrupt leaving the code of an ``exec`` or ``eval``
    of a string (``run_eval_code_obj``), and ``python -m`` then ends the process by
    SIGINT at exit, whatever status the program chose. A Ctrl-C that lands while a
    dataclass or named tuple is created (their methods are ``exec``'d from text: many
    at import) was caught and said as exit 130, yet ``python -m tactilevision`` died
    by the signal (status -2; batch interrupted 0.95 to 1.1 s after its start, during
    its imports: 4 runs of 32, 2026-11-26). The record is cleared by the next ``exec``
    of a string that completes: this one.
    """
    exec("None")  # resets CPython's unhandled-interrupt flag (docstring)


#: Set by the first Ctrl-C of a command-line run (:class:`_interrupts`).
INTERRUPTED = threading.Event()

#: Seconds an interrupt may take to unwind before the command line exits regardless
#: (under a second, process teardown included).
INTERRUPT_GRACE_S = 0.8


class _interrupts:
    """Ctrl-C honoured within :data:`INTERRUPT_GRACE_S`: the first SIGINT raises
    KeyboardInterrupt as Python does and arms a watchdog; should the exception be
    swallowed (raised inside a finalizer, "Exception ignored in ...") or the unwinding
    hang, the watchdog removes the open staging folders (nothing half-written is left),
    prints one line and exits with status 130. A KeyboardInterrupt that Python would
    print and ignore (a finalizer, a weakref or garbage-collector callback, a generator
    closed by the collector) is not printed but sent again, to be raised in the
    command's own code once that callback has returned."""

    def __init__(self, command: str) -> None:
        self.command = command
        self.previous = None
        self.unraisable = None
        self.armed = False
        self.said = False
        self.timer: threading.Timer | None = None

    def __enter__(self) -> _interrupts:
        INTERRUPTED.clear()
        self.unraisable = sys.unraisablehook
        sys.unraisablehook = self._on_unraisable
        if threading.current_thread() is threading.main_thread():
            self.previous = signal.signal(signal.SIGINT, self._on_sigint)
        return self

    def __exit__(self, *exc) -> bool:
        if self.armed:
            # interrupted and unwound (the command said so): the watchdog stays armed, so
            # that a slow shutdown (a Dask cluster closing) still ends within the grace,
            # and a further SIGINT (a second Ctrl-C, or the one re-sent from a finalizer)
            # is ignored: raised during the interpreter's shutdown it would end the process
            # by the signal (status -2) instead of 130
            self.said = True
            if threading.current_thread() is threading.main_thread():
                signal.signal(signal.SIGINT, signal.SIG_IGN)
            return False
        sys.unraisablehook = self.unraisable
        if self.previous is not None:
            signal.signal(signal.SIGINT, self.previous)
        return False

    def _on_sigint(self, signum, frame):
        INTERRUPTED.set()
        if not self.armed:
            self.armed = True
            self.timer = threading.Timer(INTERRUPT_GRACE_S, self._hard_exit)
            self.timer.daemon = True
            self.timer.start()
        if _in_finalizer(frame):
            # raised here it would be printed and ignored ("Exception ignored in ..."):
            # the signal is sent again a moment later, once the finalizer has returned
            _send_again()
            return
        raise KeyboardInterrupt

    def _on_unraisable(self, unraisable) -> None:
        """``sys.unraisablehook``: a KeyboardInterrupt raised where Python ignores
        exceptions (a callback :func:`_in_finalizer` does not know) is sent again rather
        than printed; anything else goes to the hook that was there."""
        if unraisable.exc_type is not None and issubclass(unraisable.exc_type,
                                                          KeyboardInterrupt):
            if not self.said:
                _send_again()
            return
        self.unraisable(unraisable)

    def _hard_exit(self) -> None:
        io = sys.modules.get("tactilevision.io")
        if io is not None:
            io.remove_staging()
        if not self.said:
            print(f"\ntactilevision {self.command}: interrupted", file=sys.stderr,
                  flush=True)
        sys.stderr.flush()
        os._exit(130)


def _send_again() -> None:
    """SIGINT to this process a moment from now (from a thread: once the callback that
    swallowed or deferred the interrupt has returned)."""
    again = threading.Timer(0.02, os.kill, (os.getpid(), signal.SIGINT))
    again.daemon = True
    again.start()


def _in_finalizer(frame) -> bool:
    """Whether `frame` runs inside a finalizer, a garbage-collector callback or a weakref
    callback (anywhere up its stack), where Python prints an exception and ignores it:
    distributed's GC diagnosis and weakref dictionaries swallowed a Ctrl-C so."""
    callbacks = {getattr(getattr(cb, "__func__", cb), "__code__", None) for cb in gc.callbacks}
    while frame is not None:
        code = frame.f_code
        if (code in callbacks or code.co_name == "__del__"
                or (code.co_name == "remove" and code.co_filename.endswith("weakref.py"))):
            return True
        frame = frame.f_back
    return False


def _run(args: argparse.Namespace) -> int:
    """Run the parsed command: the exit status, bad input and interrupts as one line."""
    try:
        for opt in FILE_OPTIONS.get(args.command, ()):  # before any work
            value = getattr(args, opt, None)
            if value is not None and str(value) != "-":
                importlib.import_module("tactilevision.io").check_output_file(
                    value, overwrite=getattr(args, "overwrite", False))
        with warnings.catch_warnings():
            warnings.showwarning = _one_line(args.command, warnings.showwarning)
            return int(args.func(args) or 0)
    except InputError as exc:
        print(f"tactilevision {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"\ntactilevision {args.command}: interrupted", file=sys.stderr)
        return 130
    except ImportError as exc:
        why = missing_extra(exc)
        if why is None and not INTERRUPTED.is_set():
            raise
        if why is None:     # an extension's import cut short by Ctrl-C: the interrupt
            print(f"\ntactilevision {args.command}: interrupted", file=sys.stderr)
            return 130
        print(f"tactilevision {args.command}: error: {why}", file=sys.stderr)
        return 2
    except Exception:
        if not INTERRUPTED.is_set():
            raise
        # a library that turns the interrupt into an error of its own ("failed to start",
        # "initialization failed"): it is the interrupt, said in one line
        print(f"\ntactilevision {args.command}: interrupted", file=sys.stderr)
        return 130


#: Each command's single-file outputs, checked before any work: a file tactilevision did
#: not write is replaced only with --overwrite (``view`` and ``live`` check their own).
FILE_OPTIONS = {"fit": ("json",), "diagnose": ("json",), "validate": ("json",),
                "calibrate": ("json",), "history": ("json",), "batch": ("json",),
                "plan": ("json", "write_design", "write_recommended"),
                "cache": ("json",)}

#: The optional extra (pyproject.toml) that installs each package imported on use.
EXTRAS = {"torch": "torch", "kornia": "torch", "onnx": "torch", "dask": "dask",
          "distributed": "dask", "zarr": "dask", "pyarrow": "dask", "plotly": "view"}


def missing_extra(exc: ImportError) -> str | None:
    """One sentence naming the optional extra a failed import needs, or None when the
    import is not one of an extra's (a broken installation: its traceback is kept)."""
    name = (exc.name or "").split(".")[0]
    if name in EXTRAS:
        return (f"this needs {name}, which is not installed: pip install "
                f"'tactilevision[{EXTRAS[name]}]'")
    if "pip install 'tactilevision[" in str(exc):
        return str(exc)
    return None


def _one_line(command: str, default):
    """A ``warnings.showwarning`` that prints an :class:`~tactilevision.InputWarning` as
    one line naming the command (other warnings as Python prints them)."""
    def show(message, category, filename, lineno, file=None, line=None):
        if issubclass(category, InputWarning):
            print(f"tactilevision {command}: warning: {message}", file=sys.stderr)
        else:
            default(message, category, filename, lineno, file, line)
    return show


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
