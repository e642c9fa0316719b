"""``python -m tactilevision`` runs the command line; so does the ``tactilevision`` script
(pyproject.toml's entry point is :func:`main`).

Nothing is imported here before the guard: the package root loads only its error classes
and version (no NumPy), and a Ctrl-C from then on, the command line's own imports
included, ends the run with one line and exit status 130, never a traceback. An interrupt
before that, while the interpreter itself starts (its ``site`` module included), is
Python's to handle.
"""

import importlib
import sys


def main() -> int:
    """Run the command line (:func:`tactilevision.cli.main`), importing it inside the guard.

    Returns
    -------
    status : int
        The command's exit status; 130 when interrupted, whenever the interrupt lands.
    """
    try:
        return importlib.import_module("tactilevision.cli").main()
    except KeyboardInterrupt:
        # before the command line's own handling began (its imports), or after it ended
        print("\ntactilevision: interrupted", file=sys.stderr)
        # CPython's record of an interrupt that left code exec'd from text (a dataclass
        # made at import) would end ``python -m`` by the signal: cleared by the next exec
        # of text that completes (tactilevision.cli._forget_caught_interrupt)
        exec("None")
        return 130


if __name__ == "__main__":
    sys.exit(main())
