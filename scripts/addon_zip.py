#!/usr/bin/env python3
"""Zips the Blender add-on (blender/raysplat_addon/) for Edit > Preferences > Add-ons > Install.

usage: addon_zip.py [OUT.zip]     (default: build/raysplat_addon.zip)
"""

import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
ADDON = ROOT / "blender" / "raysplat_addon"


def make_zip(out):
    out = Path(out)
    out.parent.mkdir(parents=True, exist_ok=True)
    with zipfile.ZipFile(out, "w", zipfile.ZIP_DEFLATED) as z:
        for f in sorted(ADDON.glob("*.py")):
            info = zipfile.ZipInfo(f"raysplat_addon/{f.name}", date_time=(2000, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, f.read_bytes())
    return out


if __name__ == "__main__":
    print(make_zip(sys.argv[1] if len(sys.argv) > 1 else ROOT / "build" / "raysplat_addon.zip"))
