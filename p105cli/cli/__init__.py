"""The p105 command group and the process-level half of the CLI contract.

``main`` maps every way a run can end onto the documented exit codes
(contract.ExitCode); subcommands only raise.
"""

from __future__ import annotations

import gc
import os
import sys
import warnings

import click

from p105cli import __version__
from .contract import (EXIT_STATUS_TEXT, STDOUT_NAME, ExitCode, InputError, PipeClosed, Settings, diag,
                       finish_outputs, is_write_error)

# Subcommands are registered here only when they work; each lives in its own module.
SUBCOMMANDS = {
    "parse": ("p105cli.cli.parse", "parse"),
    "export": ("p105cli.cli.export", "export"),
    "validate": ("p105cli.cli.validate", "validate"),
    "graph": ("p105cli.cli.graph", "graph"),
    "convert-dh-su": ("p105cli.cli.convert_dh_su", "convert_dh_su"),
    "interpolate": ("p105cli.cli.interpolate", "interpolate"),
    "solve": ("p105cli.cli.solve", "solve"),
}

VERSION_PACKAGES = ("click", "numpy", "scipy", "rich")


class LazyGroup(click.Group):
    """Imports a subcommand's module only when that subcommand runs (fast start-up)."""

    def list_commands(self, ctx):
        return sorted(SUBCOMMANDS)

    def get_command(self, ctx, name):
        if name not in SUBCOMMANDS:
            return None
        import importlib
        module, attr = SUBCOMMANDS[name]
        return getattr(importlib.import_module(module), attr)


def _show_versions(ctx, param, value):
    if not value or ctx.resilient_parsing:
        return
    from importlib import metadata
    import platform
    click.echo(f"p105 {__version__}")
    click.echo(f"python {platform.python_version()} ({sys.executable})")
    for name in VERSION_PACKAGES:
        try:
            click.echo(f"{name} {metadata.version(name)}")
        except metadata.PackageNotFoundError:
            click.echo(f"{name} not installed")
    ctx.exit(0)


@click.group(cls=LazyGroup, context_settings={"help_option_names": ["-h", "--help"]},
             epilog=EXIT_STATUS_TEXT)
@click.version_option(__version__, "--version", prog_name="p105", message="%(prog)s %(version)s")
@click.option("--show-versions", is_flag=True, expose_value=False, is_eager=True, callback=_show_versions,
              help="Show the versions of p105, Python and the libraries it uses, and exit.")
@click.option("-v", "--verbose", count=True, help="More diagnostics; tracebacks for internal errors.")
@click.option("-q", "--quiet", is_flag=True, help="Only errors on stderr.")
def cli(verbose, quiet):
    """p105: Unix-style filters for mechanism kinematics in ISO 10303-105 (STEP Part 105) data.

    Each subcommand reads a Part 21 file or a p105/1 JSON model (sniffed)
    from FILE or stdin and writes data, and only data, to stdout.
    """
    Settings.verbosity = -1 if quiet else verbose
    if verbose > 1:  # numpy's floating-point warnings, for whoever debugs a computation
        warnings.filterwarnings("default", category=RuntimeWarning)


def _quiet_broken_pipe() -> int:
    # Point stdout at /dev/null so the interpreter's final flush cannot fail loudly.
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except OSError:
        pass
    return ExitCode.BROKEN_PIPE


def _fewer_collections() -> None:
    # A model is hundreds of thousands of small acyclic objects (records, instances): with the
    # default thresholds the cyclic collector rescans them over and over while they are built,
    # 15 % of a 10,000-pair solve. Collections still run, a hundred times less often.
    gc.set_threshold(100_000, 50, 100)


def _single_threaded_blas() -> None:
    # p105's linear algebra is many small matrices (6 x pairs, 4 x 4 batches): BLAS threads only
    # cost, and on a busy 2-core machine they made one 120 x 300 SVD 100 times slower. numpy is
    # not imported before a subcommand runs, so this takes effect; a user's own setting wins.
    for var in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ.setdefault(var, "1")


def _step_error():
    # What `except` matches for a Part 21 error, looked up only when something was raised: the
    # step package is not imported for --version or --help, and without it nothing raised one.
    errors = sys.modules.get("p105cli.step.errors")
    return errors.StepError if errors is not None else ()


def main(argv: list[str] | None = None) -> int:
    """Run the p105 CLI and return its exit code.

    The -o outputs are renamed into place here, once the exit status is known
    (contract.finish_outputs)."""
    _single_threaded_blas()
    _fewer_collections()
    Settings.reset()
    code = ExitCode.INTERNAL
    try:
        with warnings.catch_warnings():
            # numpy's RuntimeWarnings (overflow in a product, an invalid tolerance) are not p105
            # diagnostics: what they signal is checked where it matters (finite inputs, finite
            # results) and reported as p105: lines; -vv shows them.
            warnings.simplefilter("ignore", RuntimeWarning)
            code = _run(argv)
    finally:
        code = finish_outputs(code)
    return code


def _run(argv: list[str] | None) -> int:
    try:
        # Without standalone mode click returns a click.exceptions.Exit's code instead of raising it.
        rv = cli.main(args=argv, prog_name="p105", standalone_mode=False)
        sys.stdout.flush()
        return rv if isinstance(rv, int) else ExitCode.OK
    except click.exceptions.Exit as stop:
        return stop.exit_code
    except InputError as err:
        err.show()
        return ExitCode.USAGE
    except click.exceptions.Abort:
        diag("error", "interrupted")
        return ExitCode.INTERRUPTED
    except click.ClickException as err:
        err.show()
        return ExitCode.USAGE if isinstance(err, click.UsageError) else err.exit_code
    except _step_error() as err:
        diag("error", str(err))
        if Settings.verbosity > 0:
            import traceback
            traceback.print_exc()
        return ExitCode.USAGE
    except (BrokenPipeError, PipeClosed):
        return _quiet_broken_pipe()
    except KeyboardInterrupt:
        diag("error", "interrupted")
        return ExitCode.INTERRUPTED
    except MemoryError:
        diag("error", "out of memory (try --stream for very large files)")
        return ExitCode.INTERNAL
    except OSError as err:
        if not is_write_error(err):
            return _internal_error(err)
        # A device that refuses the data (a full disk): the environment's failure, not p105's.
        # -o outputs name their path (contract.open_output); what is left is stdout.
        diag("error", f"{err.filename or STDOUT_NAME}: cannot write: {err.strerror or err}")
        return ExitCode.USAGE
    except Exception as err:  # noqa: BLE001 - the last line of defence of the contract
        from p105cli.schema.profiles import UnknownSchemaError
        if isinstance(err, UnknownSchemaError):  # the input's FILE_SCHEMA: the user's file, not a bug
            diag("error", str(err))
            return ExitCode.USAGE
        return _internal_error(err)


def _internal_error(err: BaseException) -> int:
    diag("error", f"internal error (a bug in p105, please report it): {type(err).__name__}: {err}")
    if Settings.verbosity > 0:
        import traceback
        traceback.print_exception(err)
    else:
        sys.stderr.write("p105: run again with -v for the traceback\n")
    return ExitCode.INTERNAL


def run() -> None:
    """The console script: :func:`main`, then end the process at once.

    Every output is complete, flushed and closed (or renamed into place) when
    main returns. What is left is tearing down the interpreter, and freeing
    a compiled schema's hundreds of thousands of small objects costs more
    than some commands' work (0.4 s of a 0.9 s ``graph`` run), so it is
    skipped."""
    code = main()
    for stream in (sys.stdout, sys.stderr):
        try:
            stream.flush()
        except (OSError, ValueError):
            pass
    os._exit(int(code))
