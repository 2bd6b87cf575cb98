"""Starts and stops a real luxeld for the Python end-to-end tests."""

import os
import pathlib
import signal
import socket
import subprocess
import tempfile
import time

from luxel_client import Client, LuxelError


def free_loopback_port():
    """A port nothing listens on right now (the kernel picks it)."""
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class Luxeld:
    """One daemon on 127.0.0.1:<free port> with a temporary --data-dir; its
    output goes to <data dir>/../luxeld.log (printed when start-up fails)."""

    def __init__(self, binary, extra_args=(), env=None, data_dir=None):
        self.binary = binary
        self.extra_args = list(extra_args)
        self.env = dict(os.environ, **(env or {}))
        self.tmp = tempfile.TemporaryDirectory(prefix="luxel_py_e2e_")
        self.data_dir = pathlib.Path(data_dir) if data_dir else pathlib.Path(self.tmp.name) / "data"
        self.log_path = pathlib.Path(self.tmp.name) / "luxeld.log"
        self.address = None
        self.process = None

    def start(self, ready_timeout=60.0, address=None):
        self.address = address or f"127.0.0.1:{free_loopback_port()}"
        args = [self.binary, "--listen", self.address, "--data-dir", str(self.data_dir),
                *self.extra_args]
        self._log = open(self.log_path, "wb")
        self.process = subprocess.Popen(args, stdout=self._log, stderr=subprocess.STDOUT,
                                        env=self.env)
        deadline = time.monotonic() + ready_timeout
        with Client(self.address) as probe:
            while True:
                if self.process.poll() is not None:
                    raise RuntimeError(f"luxeld exited with {self.process.returncode} during start-up:\n"
                                       + self.log())
                try:
                    probe.wait_ready(timeout=1.0)
                    return self
                except LuxelError:
                    if time.monotonic() > deadline:
                        raise RuntimeError(f"luxeld did not answer within {ready_timeout} s:\n" + self.log())

    def log(self):
        return self.log_path.read_text(errors="replace") if self.log_path.exists() else ""

    def stop(self, timeout=60.0):
        """SIGTERM, then wait; returns the exit status (SIGKILL after ``timeout``, -9)."""
        if self.process is None or self.process.poll() is not None:
            return self.process.returncode if self.process else None
        self.process.send_signal(signal.SIGTERM)
        try:
            return self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.process.kill()
            return self.process.wait()

    def cleanup(self):
        if self.process is not None and self.process.poll() is None:
            self.process.kill()
            self.process.wait()
        if self.process is not None:
            self._log.close()
        self.tmp.cleanup()
