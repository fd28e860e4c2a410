"""Tangle the literate sources of ident (``literate/*.md``) into ``src/ident/``.

The chunks are read and checked by ``chunks.read_web``; this module expands each root chunk
(references replaced by the chunks they name, indented), writes the files and maps a generated
line back to its literate line (``--where``).

Usage::

    python tangle.py            # write every root chunk to its file
    python tangle.py --check    # exit 1 and name each file that differs from the literate sources
    python tangle.py --where src/ident/hankel.py:42   # which literate line produced that line
    python tangle.py --where /abs/path/src/ident/hankel.py:42   # the same, from a traceback

The tangler reads UTF-8 (a byte-order mark is allowed), writes only ``.py`` files inside
``src/ident/`` (and ``literate_tools/tangled/``, the examples' helpers: ``OUTPUT_DIRS``) and removes
only generated files there whose root chunk is gone, and writes all
files or none: a refusal changes nothing and names the literate ``file:line`` behind it (or the
option).  Each file is written to a temporary beside it and moved into place, so that an
interrupted run leaves no partly written file.  Chunks may nest to any depth; a chunk whose
expansion would exceed ``MAX_EXPANDED_LINES`` lines or ``MAX_EXPANDED_CHARS`` characters (a chunk
included several times at each of several nested levels grows exponentially) is refused, naming
it, before anything is expanded.

Standard library only: the tangler must run before anything is installed.  The weave
(``literate_tools.site``) imports the parser and this module; they never import it.
"""
from __future__ import annotations

import argparse
import contextlib
import os
import signal
import sys
from pathlib import Path

from literate_tools.chunks import (GENERATED_MARK, OUTPUT_DIRS, PACKAGE_DIR, REFERENCE, Location, TangleError, Web,
                                   check_root, expanded_sizes, expansion_error, is_root, normalise_name, output_dir,
                                   read_web, too_large)


def expand(web: Web, name: str, indent: str = "") -> list[tuple[str, Location | None]]:
    """The lines of chunk ``name`` with references expanded, each with the literate line it came from
    (an explicit stack of the chunks being expanded, so that deep nesting is no limit); a chunk
    whose expansion is over the limits is refused before anything is built."""
    lines, chars = expanded_sizes(web, [name])[name]
    if too_large(lines, chars + lines * len(indent)):
        raise TangleError(expansion_error(web, name, lines, chars + lines * len(indent)))
    out: list[tuple[str, Location | None]] = []
    pending = [(chunk_lines(web, name), indent)]
    while pending:
        lines, indent = pending[-1]
        item = next(lines, None)
        if item is None:
            pending.pop()
        elif item[0] == "reference":
            _, target, extra = item
            pending.append((chunk_lines(web, target), indent + extra))
        else:
            _, line, location = item
            out.append(((indent + line).rstrip(), location))
    return out


def chunk_lines(web: Web, name: str):
    """("line", text, location) for each line of a chunk's pieces, with a header comment per piece,
    and ("reference", name, indentation) for each reference."""
    for block in web.pieces[name]:
        marker = "+=" if block.continued else "="
        header = Location(block.location.file, block.location.line + 1)
        yield "line", f"# <<{name}>>{marker} {block.body_location}", header
        for offset, line in enumerate(block.lines):
            match = REFERENCE.match(line)
            if match:
                yield "reference", normalise_name(match["name"]), match["indent"]
            else:
                yield "line", line, Location(block.location.file, block.body_location.line + offset)


def render(web: Web, root_name: str) -> tuple[str, list[Location | None]]:
    """File content of a root chunk and, per output line, the literate line it came from."""
    lines = expand(web, root_name)
    sources = sorted({loc.file for _, loc in lines if loc is not None},
                     key=lambda f: (f != web.pieces[root_name][0].location.file, f))
    header = (f"{GENERATED_MARK}{', '.join(sources)}.\n"
              "# Do not edit: change the literate source and run `python tangle.py`.")
    while lines and lines[-1][0] == "":
        lines.pop()
    text = header + "\n" + "\n".join(line for line, _ in lines) + "\n"
    return text, [None, None] + [loc for _, loc in lines]


def tangle(root: Path) -> tuple[dict[str, str], Web]:
    """Map each generated file (relative path) to its content."""
    web = read_web(root)
    return {name: render(web, name)[0] for name in web.roots()}, web


def generated_on_disk(root: Path) -> list[str]:
    """Files under src/ident (and the other OUTPUT_DIRS) that carry the generated-file header."""
    found = []
    for path in sorted(path for folder in OUTPUT_DIRS if (root / folder).is_dir() for path in (root / folder).rglob("*.py")):
        try:
            with path.open("rb") as handle:
                generated = handle.readline().startswith(GENERATED_MARK.encode())
        except OSError:
            continue  # a folder named *.py, a broken link: not a generated file
        if generated:
            found.append(path.relative_to(root).as_posix())
    return found


def differences(root: Path, outputs: dict[str, str]) -> list[str]:
    """One line per file that is out of date, missing, or generated without a root chunk."""
    problems = []
    for name, text in outputs.items():
        path = root / name
        if not path.exists():
            problems.append(f"{name}: missing (run python tangle.py)")
        elif not path.is_file():
            problems.append(f"{name}: is not a file (a folder?) where a generated file belongs")
        elif path.read_bytes() != text.encode("utf-8"):
            problems.append(f"{name}: differs from what the literate sources produce")
    for name in generated_on_disk(root):
        if name not in outputs:
            problems.append(f"{name}: generated file has no root chunk in literate/ any more")
    return problems


def inside(folder: Path, path: Path) -> bool:
    """Whether path, with links and '..' resolved, is the (resolved) folder or lies in it."""
    resolved = path.resolve()
    return resolved == folder or folder in resolved.parents


TEMPORARY_SUFFIX = ".tangle-new"


def temporary_beside(path: Path, suffix: str = TEMPORARY_SUFFIX) -> Path:
    """The temporary file for ``path``: in the same folder (so that ``os.replace`` moves it into place in
    one step, and a reader sees the old file or the new one, never part of one)."""
    return path.with_name(f".{path.name}{suffix}")


def remove_leftover_temporaries(package: Path) -> None:
    """Remove the temporaries a killed run left in an output folder (its own names only, ``.NAME.py.tangle-new``)."""
    if package.is_dir():
        for path in package.rglob(f".*.py{TEMPORARY_SUFFIX}"):
            if path.is_file() and not path.is_symlink():
                with contextlib.suppress(OSError):  # housekeeping: one it cannot remove does no harm
                    path.unlink()


def replace_bytes(path: Path, data: bytes, suffix: str = TEMPORARY_SUFFIX) -> None:
    """Write ``data`` to ``path`` through a temporary beside it: the file is whole at every moment."""
    temporary = temporary_beside(path, suffix)
    try:
        temporary.write_bytes(data)
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def put_back(undo: list, made: list, suffix: str = TEMPORARY_SUFFIX) -> None:
    """Undo a write that failed or was interrupted: each (path, previous bytes or None for a new file)
    in reverse order, then the folders it made if they are empty again."""
    for path, previous in reversed(undo):
        if previous is None:
            path.unlink(missing_ok=True)
        else:
            replace_bytes(path, previous, suffix)
    for folder in reversed(made):
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()


def write(root: Path, outputs: dict[str, str], origins: dict[str, Location] | None = None) -> list[str]:
    """Write changed files and remove stale generated ones, all or nothing; return what was changed.

    Every new content is first written to a temporary file beside its target; only when all are
    written are they moved into place (``os.replace``, so that no file is ever partly written) and
    the stale files removed, and a failure or an interrupt on the way puts back what was there
    before and removes the temporaries (those a killed run left are removed by the next run).
    Nothing outside src/ident/ (and the other OUTPUT_DIRS) is written or removed. A refusal is a TangleError naming the root
    chunk's file:line (from ``origins``) or the generated file.
    """
    origins = origins or {}

    def folder(name: str) -> Path:
        return (root / output_dir(name)).resolve()

    def culprit(name: str) -> str:
        return f"{origins[name]}: " if name in origins else f"{name}:1: "

    changes = []
    for name, text in outputs.items():
        path = root / name
        if not is_root(name) or not inside(folder(name), path):
            raise TangleError(f"{culprit(name)}{name} lies outside {output_dir(name) or PACKAGE_DIR}/ (through '..' "
                              "or a symbolic link); nothing was written")
        if path.is_dir():
            raise TangleError(f"{culprit(name)}{name} is a folder; nothing was written")
        if not path.is_file() or path.read_bytes() != text.encode("utf-8"):
            changes.append((name, path, text))
    stale = [name for name in generated_on_disk(root) if name not in outputs]
    if stale and not outputs:
        raise TangleError(f"{root / 'literate'}: no root chunk (<<{PACKAGE_DIR}/FILE.py>>=) in any document; "
                          f"refusing to remove the {len(stale)} generated file(s) of {PACKAGE_DIR}/")
    stale = [name for name in stale if inside(folder(name), (root / name).parent)]  # a link itself, not its target
    undo: list[tuple[Path, bytes | None]] = []  # what each done step replaced, in order
    temporaries: list[Path] = []
    made: list[Path] = []  # folders that do not exist yet, outermost first
    for folder in dict.fromkeys(path.parent for _, path, _ in changes):
        made.extend(f for f in reversed([folder, *folder.parents]) if not f.exists() and f not in made)
    current = None
    for output in OUTPUT_DIRS:
        remove_leftover_temporaries(root / output)
    try:
        for current, path, text in changes:
            path.parent.mkdir(parents=True, exist_ok=True)
            temporaries.append(temporary_beside(path))
            with temporaries[-1].open("w", encoding="utf-8", newline="\n") as handle:
                handle.write(text)
        for (current, path, _), temporary in zip(changes, temporaries):
            undo.append((path, path.read_bytes() if path.is_file() else None))
            os.replace(temporary, path)
        for current in stale:
            undo.append((root / current, (root / current).read_bytes()))
            (root / current).unlink()
    except BaseException as error:  # an OSError, or an interrupt (Ctrl-C): put everything back first
        for temporary in temporaries:
            temporary.unlink(missing_ok=True)
        put_back(undo, made)
        if not isinstance(error, OSError):
            raise
        raise TangleError(f"{culprit(current)}cannot write {current} ({error.strerror or error}); "
                          "nothing was changed") from None
    return [f"wrote {name}" for name, _, _ in changes] + [f"removed {name} (no root chunk)" for name in stale]


def where(root: Path, target: str) -> str:
    """The literate line that produced ``file:line`` of a generated file."""
    name, _, number = target.rpartition(":")
    if not name or not number.isdigit():
        raise TangleError(f"--where expects FILE:LINE, got {target!r}")
    name = package_file(root, name)
    web = read_web(root)
    if name not in web.pieces:
        raise TangleError(f"{name} is not produced by any root chunk")
    _, locations = render(web, name)
    index = int(number) - 1
    if not 0 <= index < len(locations):
        raise TangleError(f"{name} has {len(locations)} lines, not {number}")
    return str(locations[index]) if locations[index] else f"{name}:{number} is the generated header"


def package_file(root: Path, name: str) -> str:
    """``src/ident/FILE.py`` for a file named as the project names it, or by a path (absolute, as a
    traceback prints it, or relative to the current directory) to a file inside ``ROOT/src/ident/``."""
    given = Path(name)
    if not given.is_absolute() and is_root(given.as_posix()) and ".." not in given.parts:
        return given.as_posix()  # the project's own name for it, whatever the current directory
    path = Path(name).resolve()
    for output in OUTPUT_DIRS:
        if path.is_relative_to((root / output).resolve()):
            return output + "/" + path.relative_to((root / output).resolve()).as_posix()
    raise TangleError(f"--where: {name} is not inside {(root / PACKAGE_DIR).resolve()}{os.sep}: only the files the "
                      f"tangler writes there (or in {', '.join(OUTPUT_DIRS[1:])}/) map back to literate/")


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["weave"]:
        print("tangle.py: error: the weave is its own program now: python weave.py", file=sys.stderr)
        return 2
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--check", action="store_true",
                        help="write nothing; exit 1 if a generated file differs from the literate sources")
    parser.add_argument("--where", metavar="FILE:LINE",
                        help="print the literate line that produced FILE:LINE (FILE as src/ident/NAME.py, "
                             "or a path to it, absolute as in a traceback or relative)")
    parser.add_argument("--root", type=Path, default=Path(__file__).resolve().parents[1],
                        help="project root holding literate/ and src/ident/ (default: this file's folder)")
    args = parser.parse_args(argv)
    try:
        check_root(args.root)
        if args.where:
            print(where(args.root, args.where))
            return 0
        outputs, web = tangle(args.root)
        for warning in web.warnings:
            print(warning, file=sys.stderr)
        if args.check:
            problems = differences(args.root, outputs)
            for problem in problems:
                print(problem)
            if problems:
                print(f"tangle.py --check: {len(problems)} file(s) out of date; run python tangle.py",
                      file=sys.stderr)
                return 1
            print(f"tangle.py --check: {len(outputs)} file(s) up to date")
            return 0
        origins = {name: web.pieces[name][0].location for name in outputs}
        with interrupt_on_sigterm():
            changes = write(args.root, outputs, origins)
        for change in changes:
            print(change)
    except TangleError as error:
        print(f"tangle.py: error: {error}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"tangle.py: interrupted; {PACKAGE_DIR}/ is left as it was", file=sys.stderr)
        return 130
    return 0


@contextlib.contextmanager
def interrupt_on_sigterm():
    """SIGTERM (a ``kill``, a CI time limit) interrupts as Ctrl-C does (a KeyboardInterrupt), so that
    a half-done write is put back (and the weave's build folder removed) instead of the process just
    ending."""
    def interrupt(signum, frame):
        raise KeyboardInterrupt

    try:
        previous = signal.signal(signal.SIGTERM, interrupt)
    except ValueError:  # not the main thread: signals cannot be caught here
        yield
        return
    try:
        yield
    finally:
        signal.signal(signal.SIGTERM, previous)
