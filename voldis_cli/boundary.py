"""The scripts' boundary: a mistake is one line naming the file and the problem, never a traceback.

Exit codes: 0 done, 1 an error (input files, settings, output folder, or an internal error), 2 a
usage error (argparse), 130 interrupted. ``--debug`` anywhere on the command line re-raises, showing
the traceback. Standard library only: the scripts choose the Mitsuba variant before importing
mi_voldis.
"""
import argparse
import os
import sys
import warnings

USER_ERRORS = ("ValueError", "OSError", "DatasetError", "FileNotFoundError", "PermissionError", "IsADirectoryError",
               "NotADirectoryError")


def one_line(error):
    """The error's message on one line. Mitsuba's errors span several, and when a plugin written in
    Python raised, they embed its traceback: then the plugin's own message (the last line) is the one.
    Dr.Jit's say "failed (see above)" and carry the reason as their cause: it follows, after a colon."""
    text = str(error)
    if "Traceback (most recent call last):" in text:
        last = [line for line in text.splitlines() if line.strip()][-1].strip()
        name, _, message = last.partition(": ")
        text = message if name.isidentifier() and message else last
    text = " ".join(text.split()) or type(error).__name__
    cause = error.__cause__ or error.__context__
    if "(see above)" in text and cause is not None and cause is not error:
        text = f"{text.replace(' (see above)', '').rstrip('.!')}: {one_line(cause)}"
    return text


def _warning_line(caught):
    """What the warnings ``caught`` while the program ran said, on one line (each once, in order)."""
    said = list(dict.fromkeys(f"{w.category.__name__}: {w.message}" for w in caught))
    return "; ".join(said)


def run(main, argv=None):
    """Run ``main(argv)`` and return the process's exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    debug = "--debug" in argv
    # numpy's RuntimeWarnings (a division by zero, an empty mean) are kept from stderr, where they add
    # lines of numpy's source for what the code expects and handles; an error names every warning before
    # it in its one line; after a run that ends well, other warnings are one line; --debug prints all as
    # Python does
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("default")
        try:
            main(argv)
        except KeyboardInterrupt:
            if debug:
                raise
            print("interrupted", file=sys.stderr)
            return 130
        except Exception as e:  # noqa: BLE001  (the boundary: everything becomes one line)
            if debug:
                raise
            kinds = {k.__name__ for k in type(e).__mro__}
            hint = "" if kinds & set(USER_ERRORS) else f" ({type(e).__name__}; run again with --debug for the " \
                                                       "traceback)"
            said = _warning_line(caught)
            print(f"error: {one_line(e)}{hint}" + (f" (after {said})" if said else ""), file=sys.stderr)
            return 1
        finally:
            for w in caught if debug else ():
                print(warnings.formatwarning(w.message, w.category, w.filename, w.lineno).rstrip(), file=sys.stderr)
    others = _warning_line([w for w in caught if not issubclass(w.category, RuntimeWarning)])
    if others and not debug:
        print(f"warning: {others}", file=sys.stderr)
    return 0


def variant_first(argv):
    """Set ``$MI_VOLDIS_VARIANT`` from ``--variant`` in ``argv`` before anything imports mi_voldis (which
    selects the Mitsuba variant when imported)."""
    pre = argparse.ArgumentParser(add_help=False)
    pre.add_argument("--variant", default="llvm_ad_rgb")
    os.environ["MI_VOLDIS_VARIANT"] = pre.parse_known_args(argv)[0].variant


def parser_of(doc, epilog=None):
    """An argument parser described by a program's docstring: its first paragraph, then the rest (or
    ``epilog``) after the options."""
    return argparse.ArgumentParser(description=doc.split("\n\n")[0],
                                   epilog=doc.split("\n\n", 1)[1] if epilog is None else epilog,
                                   formatter_class=argparse.RawDescriptionHelpFormatter)


def check_run(path):
    """A run folder must exist (one line naming it otherwise)."""
    if not os.path.isdir(path):
        raise ValueError(f"{path}: no such run folder (scripts/train.py writes one)")


def add_debug(parser):
    parser.add_argument("--debug", action="store_true", help="show the traceback of an error")


def add_threads(parser):
    parser.add_argument("--threads", type=positive, default=None, metavar="N",
                        help="CPU threads of the LLVM variants (default: all cores); with 1 a run repeats bit for "
                             "bit (more threads add atomically, in varying order)")


def set_threads(args):
    """Apply ``--threads`` to Dr.Jit's thread pool (the LLVM backend's; the CUDA variants ignore it);
    more threads than cores are allowed, with a warning (they only contend: many times slower)."""
    cores = os.cpu_count() or 1
    if args.threads and args.threads > cores:
        print(f"warning: --threads {args.threads} is more than the {cores} cores here; threads beyond the cores "
              "only slow the run down", file=sys.stderr)
    if args.threads:
        import drjit as dr
        dr.set_thread_count(args.threads)


def positive(text):
    """argparse type: a whole number >= 1 (0 or less is a usage error, not "the default")."""
    try:
        value = int(text)
    except ValueError:
        value = 0
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be a whole number >= 1, got '{text}'")
    return value
