"""``python -m docs.generate check|update [DOCUMENT ...]``: regenerate every region of the
documents (README.md and docs/*.md by default); ``check`` prints a unified diff of each
region that drifted and exits 1, ``update`` rewrites them."""

from __future__ import annotations

import argparse
import difflib
import sys
import time
from collections.abc import Iterator
from pathlib import Path

from . import parallel
from .generators import GENERATORS, render, same
from .regions import RegionError, find_regions, replace_bodies
from .session import ROOT, Session


def documents() -> list[Path]:
    """The README and every page of docs/."""
    return [ROOT / "README.md", *sorted((ROOT / "docs").glob("*.md"))]


def process(path: Path, update: bool) -> tuple[int, list[str], list[str]]:
    """Regenerate the regions of ``path`` (rewritten in place when ``update``); returns
    the number of regions and the reports of those that drifted and those that failed."""
    text = path.read_text()
    shown = path.relative_to(ROOT) if path.is_relative_to(ROOT) else path
    regions = find_regions(shown, text)
    drifted, failed, bodies = [], [], []
    session = Session()
    try:
        for region in regions:
            if region.name not in GENERATORS:
                raise RegionError(f"{region.where}: no generator named {region.name!r}")
            try:
                fresh = render(region, session)
            except Exception as error:  # a broken generator is reported with its region
                failed.append(f"{region.where}: {region.name} failed: {error!r}")
                bodies.append(region.body)
                continue
            if same(region, fresh):
                bodies.append(region.body)
                continue
            bodies.append(fresh)
            diff = difflib.unified_diff(
                region.body.splitlines(keepends=True),
                fresh.splitlines(keepends=True),
                f"{region.where} (the document)",
                f"{region.where} ({region.name}, today)",
            )
            drifted.append(f"{region.where}: region {region.name!r} drifted\n{''.join(diff)}")
    finally:
        session.close()
    if update and bodies != [r.body for r in regions]:
        path.write_text(replace_bodies(text, regions, bodies))
    return len(regions), drifted, failed


def prefetch(paths: list[Path]) -> None:
    """Start in the background the simulations of every generator the documents name
    (refusing an unknown one), so that they run while the first documents are made."""
    started = set()
    for path in paths:
        for region in find_regions(path):
            generator = GENERATORS.get(region.name)
            if generator is None:
                raise RegionError(f"{region.where}: no generator named {region.name!r}")
            if generator.prefetch is not None and generator.prefetch not in started:
                generator.prefetch()
                started.add(generator.prefetch)


def waits(path: Path) -> bool:
    """Whether a region of ``path`` is made from the simulations run in the background
    (its generator has a prefetch)."""
    return any(GENERATORS[region.name].prefetch is not None for region in find_regions(path))


def in_order(paths: list[Path], update: bool) -> Iterator[tuple[int, list[str], list[str]]]:
    """What :func:`process` finds of each document, in the order of ``paths``; the documents
    that wait for the background simulations are made last, so that this process makes the
    others (their console blocks) while the simulations run."""
    done: dict[int, tuple[int, list[str], list[str]]] = {}
    shown = 0
    for index in sorted(range(len(paths)), key=lambda i: waits(paths[i])):
        done[index] = process(paths[index], update)
        while shown in done:
            yield done.pop(shown)
            shown += 1


def main(argv: list[str] | None = None) -> int:
    """Check or update; the exit code is 1 when a region drifted (check) or failed."""
    parser = argparse.ArgumentParser(prog="python -m docs.generate", description=__doc__)
    parser.add_argument("action", choices=("check", "update"))
    parser.add_argument("documents", nargs="*", type=Path)
    options = parser.parse_args(argv)
    start = time.perf_counter()
    paths = [p.resolve() for p in options.documents] or documents()
    drifted, failed, count = 0, 0, 0
    try:
        prefetch(paths)
        for regions, drifts, failures in in_order(paths, options.action == "update"):
            print("\n".join([*drifts, *failures]), end="\n" if drifts or failures else "")
            count, drifted = count + regions, drifted + len(drifts)
            failed += len(failures)
    except RegionError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    finally:
        parallel.shutdown()
    verb = "rewritten" if options.action == "update" else "drifted"
    print(
        f"{count} generated regions in {len(paths)} documents: {drifted} {verb}, "
        f"{failed} failed ({time.perf_counter() - start:.0f} s)"
    )
    return 1 if failed or (drifted and options.action == "check") else 0


if __name__ == "__main__":
    sys.exit(main())
