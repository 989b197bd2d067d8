#!/usr/bin/env python3
"""Writes the option lists of docs/usage.md from the command's own --help, between the markers
<!-- options:begin … --> and <!-- options:end -->. tests/cli_test.py checks that they agree.

usage: update_usage.py [RAYSPLAT]     (default: $RAYSPLAT, else build/raysplat)
"""

import os
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
USAGE = ROOT / "docs" / "usage.md"
BEGIN, END = "<!-- options:begin", "<!-- options:end -->"
COMMANDS = ("render", "voxelize", "info", "compare")


def options_block(raysplat):
    """The markdown between the markers: each command's --help in a code block."""
    parts = []
    for command in COMMANDS:
        text = subprocess.run([raysplat, command, "--help"], capture_output=True, text=True, check=True).stdout
        parts.append(f"### raysplat {command}\n\n```\n{text.rstrip()}\n```\n")
    return "\n".join(parts)


def split(text):
    """(before, between, after) around the markers' lines."""
    b = text.index(BEGIN)
    b = text.index("\n", b) + 1
    e = text.index(END)
    return text[:b], text[b:e], text[e:]


def main():
    raysplat = sys.argv[1] if len(sys.argv) > 1 else os.environ.get("RAYSPLAT", str(ROOT / "build" / "raysplat"))
    before, _, after = split(USAGE.read_text())
    USAGE.write_text(before + options_block(raysplat) + after)
    print(f"wrote the option lists of {USAGE}")


if __name__ == "__main__":
    main()
