#!/usr/bin/env python3
"""Copies the bench's tables into docs/SOLVERS.md, between its marker lines, so the figures
there are the ones `knitfit bench` wrote:

    knitfit bench --out docs                      # docs/bench.{md,csv,png}, about 15 minutes
    knitfit bench --quick --out /tmp/quick        # then copy its bench.* to docs/bench-quick.*
    python3 tools/embed_bench.py

Reads docs/bench.md and docs/bench-quick.md; the test `docs::solvers_md_embeds_the_bench_tables`
fails while docs/SOLVERS.md holds anything else between the markers."""
import pathlib
import re
import sys

DOCS = pathlib.Path(__file__).resolve().parent.parent / "docs"
SECTIONS = [
    ("bench.md", "bench.md begins", "bench.md ends"),
    ("bench-quick.md", "bench-quick.md begins", "bench-quick.md ends"),
]


def main() -> int:
    solvers = DOCS / "SOLVERS.md"
    text = solvers.read_text()
    for name, begins, ends in SECTIONS:
        table = (DOCS / name).read_text()
        pattern = re.compile(
            r"(<!-- " + re.escape(begins) + r"[^\n]*-->\n)(.*?)(<!-- " + re.escape(ends) + r" -->)",
            re.S,
        )
        if not pattern.search(text):
            print(f"docs/SOLVERS.md has no markers for {name}", file=sys.stderr)
            return 1
        text = pattern.sub(lambda m: m.group(1) + table + m.group(3), text)
    solvers.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
