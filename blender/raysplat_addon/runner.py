"""Runs the raysplat command for the add-on: no bpy here, so that it can be used and tested
outside Blender. The command reports with --progress json (one JSON object a line on stderr)
and stops cleanly on SIGINT, removing what it had staged."""

import json
import os
import shutil
import signal
import subprocess
import threading
import time

ERROR_PREFIX = "raysplat: error: "


class RaysplatError(Exception):
    """A failure to show the user: the command's own one-line message where it gave one."""


def find_binary(configured=""):
    """The raysplat binary: the configured path, else the one on PATH."""
    if configured:
        path = os.path.abspath(os.path.expanduser(configured))
        if not (os.path.isfile(path) and os.access(path, os.X_OK)):
            raise RaysplatError(f"raysplat binary not found: {path} (set it in the add-on's preferences)")
        return path
    found = shutil.which("raysplat")
    if not found:
        raise RaysplatError("raysplat binary not found on PATH (set its path in the add-on's preferences)")
    return found


_defaults = {}


def cli_defaults(binary):
    """The render command's defaults, as `raysplat render --defaults` prints them (cached)."""
    if binary not in _defaults:
        out = subprocess.run([binary, "render", "--defaults"], capture_output=True, text=True, timeout=30)
        if out.returncode != 0:
            raise RaysplatError(last_error(out.stderr.splitlines()) or f"{binary} render --defaults failed")
        _defaults[binary] = json.loads(out.stdout)
    return _defaults[binary]


def last_error(lines):
    """The command's one-line error among its stderr lines, or None."""
    for line in reversed(lines):
        if line.startswith(ERROR_PREFIX):
            return line[len(ERROR_PREFIX):].strip()
    for line in reversed(lines):
        if line.startswith("raysplat: ") and "stopped" in line:
            return line[len("raysplat: "):].strip()
    return None


class Run:
    """One running command. `events` are its JSON lines, parsed, in order; `lines` every
    stderr line. poll() returns the exit status or None."""

    def __init__(self, cmd):
        self.cmd = cmd
        self.lines = []
        self.events = []
        self._lock = threading.Lock()
        try:
            self.proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                                         start_new_session=True)
        except OSError as e:
            raise RaysplatError(f"cannot run {cmd[0]}: {e.strerror}") from e
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stderr:
            line = line.rstrip("\n")
            event = None
            if line.startswith("{"):
                try:
                    event = json.loads(line)
                except ValueError:
                    event = None
            with self._lock:
                self.lines.append(line)
                if event is not None:
                    self.events.append(event)

    def take_events(self, start):
        with self._lock:
            return self.events[start:]

    def stop(self, grace=30.0):
        """SIGINT, as Esc asks; the command removes its staged outputs and exits. Killed if it
        has not ended after `grace` seconds."""
        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
            try:
                self.proc.wait(grace)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        self._reader.join(5.0)

    def wait(self):
        status = self.proc.wait()
        self._reader.join(5.0)
        return status


def run(cmd, on_event=None, should_stop=None, poll=0.05):
    """Runs `cmd` (which must include --progress json) to its end. on_event(event) sees every
    JSON event; should_stop() is asked between them and, when true, stops the command and
    returns False. Raises RaysplatError with the command's own message when it fails."""
    r = Run(cmd)
    seen = 0
    try:
        while True:
            status = r.proc.poll()
            events = r.take_events(seen)
            seen += len(events)
            for e in events:
                if on_event:
                    on_event(e)
            if status is not None:
                r.wait()
                for e in r.take_events(seen):
                    if on_event:
                        on_event(e)
                break
            if should_stop and should_stop():
                r.stop()
                return False
            time.sleep(poll)
    except BaseException:
        r.stop()
        raise
    if status != 0:
        message = last_error(r.lines) or f"{os.path.basename(cmd[0])} exited with status {status}"
        raise RaysplatError(message)
    return True


class FrameRun:
    """One command rendering a walkthrough (--frames A-B [--frame-step N] --progress json, -o with
    '#'s) for Blender's Render Animation, which asks for its frames one at a time, in order.
    `output(frame)` is frame's file; a frame is done when its file exists, since the command
    writes each frame whole, by a rename, when it is done."""

    def __init__(self, cmd, output):
        self.output = output
        self.run = Run(cmd)
        self._seen = 0

    def wait_frame(self, frame, on_event=None, should_stop=None, poll=0.05):
        """Waits until `frame`'s file is written and returns its path; on_event sees the events
        meanwhile. Returns None, the command stopped, when should_stop() says so. Raises
        RaysplatError with the command's message when it ends without writing the frame."""
        path = self.output(frame)
        while True:
            status = self.run.proc.poll()
            events = self.run.take_events(self._seen)
            self._seen += len(events)
            for e in events:
                if on_event:
                    on_event(e)
            if os.path.exists(path):
                return path
            if status is not None:
                self.run.wait()
                if os.path.exists(path):
                    return path
                message = last_error(self.run.lines) if status != 0 else None
                raise RaysplatError(message or f"{os.path.basename(self.run.cmd[0])} ended (status {status}) "
                                                f"without writing frame {frame}")
            if should_stop and should_stop():
                self.stop()
                return None
            time.sleep(poll)

    def stop(self):
        self.run.stop()

    def finish(self):
        """Waits for the command's end (its last frame handed over); raises on a failure."""
        status = self.run.wait()
        if status != 0:
            raise RaysplatError(last_error(self.run.lines) or f"{os.path.basename(self.run.cmd[0])} exited with status {status}")


def describe(event):
    """A status line for Blender's header from a progress event."""
    if event.get("event") != "progress":
        return None
    frame = f"frame {event['frame']}: " if "frame" in event else ""
    text = f"raysplat: {frame}{event.get('stage', '')} {event.get('done', 0)}/{event.get('total', 0)}"
    if "inner" in event:
        text += f" · {event['inner']} {int(100 * event.get('inner_fraction', 0))} %"
    return text
