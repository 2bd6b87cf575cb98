"""Runs the `luxel` command line tool without blocking Blender's UI.

The add-on talks to luxeld through `luxel` rather than through gRPC from
Blender's Python: Blender ships neither grpcio nor protobuf, and the CLI's
`--json` mode (one JSON object per line: scene, bake, event, artifact,
result) already carries everything an editor needs. The only thing the
add-on has to know about an installation is where the binary is. No bpy
here: the reader threads must not touch Blender data."""

import json
import os
import queue
import signal
import subprocess
import threading

# Exit codes of `luxel` (docs/api.md): 0 done, 1 error, 2 usage, 3 the bake
# ended FAILED or CANCELLED.
EXIT_OK, EXIT_ERROR, EXIT_USAGE, EXIT_BAKE_FAILED = 0, 1, 2, 3


def token_env(token_file):
    """The environment for `luxel`: the bearer token goes in LUXEL_TOKEN,
    never on the command line, where every user of the machine sees it."""
    env = dict(os.environ)
    env.pop("LUXEL_TOKEN", None)
    if token_file:
        path = os.path.expanduser(token_file)
        try:
            with open(path, encoding="utf-8") as f:
                token = f.read().strip()
        except OSError as e:
            raise RuntimeError(f"cannot read the token file {path}: {e.strerror}") from None
        if not token:
            raise RuntimeError(f"the token file {path} is empty")
        env["LUXEL_TOKEN"] = token
    return env


class Process:
    """One `luxel` invocation. Threads drain stdout and stderr, so a chatty
    process never blocks on a full pipe; poll() hands the main thread the
    lines read so far (JSON lines parsed, others as text)."""

    def __init__(self, args, env=None):
        self.args = [str(a) for a in args]
        self._lines = queue.Queue()
        self._stderr = []
        try:
            self._proc = subprocess.Popen(self.args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                          stdin=subprocess.DEVNULL, env=env, text=True, bufsize=1,
                                          start_new_session=True)
        except OSError as e:
            raise RuntimeError(f"cannot run {self.args[0]}: {e.strerror}") from None
        self._threads = [threading.Thread(target=self._read_stdout, daemon=True),
                         threading.Thread(target=self._read_stderr, daemon=True)]
        for t in self._threads:
            t.start()

    def _read_stdout(self):
        for line in self._proc.stdout:
            line = line.strip()
            if not line:
                continue
            try:
                self._lines.put(json.loads(line))
            except ValueError:
                self._lines.put({"type": "text", "text": line})
        self._proc.stdout.close()

    def _read_stderr(self):
        for line in self._proc.stderr:
            self._stderr.append(line.rstrip("\n"))
        self._proc.stderr.close()

    def poll(self):
        """Lines read since the last call, oldest first."""
        out = []
        while True:
            try:
                out.append(self._lines.get_nowait())
            except queue.Empty:
                return out

    @property
    def returncode(self):
        """None while running, and until every line it wrote has been read."""
        if self._proc.poll() is None:
            return None
        for t in self._threads:
            t.join(timeout=1.0)
        return self._proc.returncode

    def stderr_text(self):
        return "\n".join(self._stderr)

    def error_line(self):
        """The message of a failed run: its last line on stderr."""
        lines = [s for s in self._stderr if s.strip()]
        return lines[-1] if lines else f"{os.path.basename(self.args[0])} exited with {self._proc.returncode}"

    def terminate(self):
        if self._proc.poll() is None:
            # Its own session (start_new_session): the signal reaches the
            # process group of this run only.
            try:
                os.killpg(self._proc.pid, signal.SIGTERM)
            except ProcessLookupError:
                pass

    def wait(self, timeout):
        try:
            self._proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self._proc.kill()
            self._proc.wait()
        return self.returncode
