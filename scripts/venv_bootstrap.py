"""Run a study script inside the project's virtual environment.

ensure() creates .venv-study/ at the repository root with scripts/requirements.txt
installed (again whenever that file changes) and re-executes the calling script with the
environment's interpreter. Call it before importing any third-party package.
"""

import hashlib
import os
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
VENV = os.path.join(ROOT, ".venv-study")
REQUIREMENTS = os.path.join(ROOT, "scripts", "requirements.txt")
STAMP = os.path.join(VENV, "requirements.sha256")


def _digest():
    with open(REQUIREMENTS, "rb") as f:
        return hashlib.sha256(f.read()).hexdigest()


def _run(cmd, what):
    try:
        subprocess.run(cmd, check=True)
    except (OSError, subprocess.CalledProcessError) as e:
        sys.exit(f"error: {what} failed ({e}); on Debian run "
                 f"'apt-get install python3-venv python3-pip' (scripts/run.sh study does)")


def ensure():
    python = os.path.join(VENV, "bin", "python")
    if os.path.realpath(sys.prefix) == os.path.realpath(VENV):
        return
    want = _digest()
    have = open(STAMP).read().strip() if os.path.exists(STAMP) else ""
    if not os.path.exists(python) or have != want:
        print(f"setting up {os.path.relpath(VENV, ROOT)}/ from scripts/requirements.txt", flush=True)
        _run([sys.executable, "-m", "venv", VENV], "python3 -m venv " + VENV)
        _run([python, "-m", "pip", "install", "--quiet", "--upgrade", "pip"], "pip upgrade")
        _run([python, "-m", "pip", "install", "--quiet", "-r", REQUIREMENTS], "pip install -r " + REQUIREMENTS)
        with open(STAMP, "w") as f:
            f.write(want + "\n")
    os.execv(python, [python] + sys.argv)
