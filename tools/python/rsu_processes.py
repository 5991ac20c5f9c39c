# SPDX-License-Identifier: Apache-2.0
"""Helpers to run the project's real processes on loopback, shared by the integration tests
(tests/integration/*.py), the load and fault tests and the realistic experiment
(eval/corridor/run_experiment.py).

  free_udp_port(ip)        a UDP port the kernel has just handed out on ip (free at that moment)
  Children                 spawns child processes with their output in files; kill_all() on the way out
  wait_for(cond, s, what)  polls cond until true or s seconds pass; fails early if a watched process exits
  wait_for_line(path, ..)  waits until a text appears in a (log) file

Every wait is bounded in time: a timeout raises TimeoutError, a watched process exiting first raises
ChildExited, both with a message saying what was awaited (callers turn them into a test failure or exit).
"""
import os
import socket
import subprocess
import time


class ChildExited(RuntimeError):
    """A process that had to stay up exited while something was awaited."""


def free_udp_port(ip="127.0.0.1"):
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind((ip, 0))
        return s.getsockname()[1]


class Children:
    """Child processes started by one run; kill_all() kills whichever are still running."""

    def __init__(self):
        self.procs = []

    def spawn(self, cmd, stdout_path, stdin_path=None, stderr_path=None, env=None, own_session=False):
        """Starts cmd with stdout to stdout_path and stderr to stderr_path (default: into stdout); env
        replaces the environment when given. own_session: in a session of its own, so that Linux's
        autogroup scheduling shares the CPU between it and this session's processes as between two
        services, not as threads of one group."""
        stdin = open(stdin_path) if stdin_path else subprocess.DEVNULL
        out = open(stdout_path, "w")
        err = open(stderr_path, "w") if stderr_path else subprocess.STDOUT
        p = subprocess.Popen(cmd, stdin=stdin, stdout=out, stderr=err, env=env, start_new_session=own_session)
        self.procs.append(p)
        return p

    def kill_all(self):
        for p in self.procs:
            if p.poll() is None:
                p.kill()
                try:
                    p.wait(timeout=5)
                except subprocess.TimeoutExpired:
                    pass


def read_text(path):
    if not os.path.exists(path):
        return ""
    with open(path) as f:
        return f.read()


def wait_for(condition, seconds, what, watch=None, watch_log=None, poll_s=0.02):
    """Polls condition() until it is true. Raises TimeoutError after `seconds`, or ChildExited as soon as
    the process `watch` has exited; either message ends with the tail of `watch_log` (a path) if given."""
    deadline = time.time() + seconds
    while time.time() < deadline:
        if condition():
            return
        if watch is not None and watch.poll() is not None:
            raise ChildExited("process exited (code %s) while waiting for %s:\n%s" % (
                watch.returncode, what, read_text(watch_log)[-4000:] if watch_log else ""))
        time.sleep(poll_s)
    raise TimeoutError("timed out after %.1f s waiting for %s%s" % (
        seconds, what, (":\n" + read_text(watch_log)[-4000:]) if watch_log else ""))


def wait_for_line(path, text, seconds, watch=None):
    """Waits until `text` appears in the file at `path` (a child's log)."""
    wait_for(lambda: text in read_text(path), seconds, "'%s' in %s" % (text, path), watch=watch, watch_log=path,
             poll_s=0.05)
