#!/usr/bin/env python3
# SPDX-License-Identifier: Apache-2.0
"""rsud started as the shipped systemd unit starts it, as far as a machine without systemd as PID 1 allows
(issue 14 item 1). The keys are made by rsu-keygen with the README's commands, as root, into a stand-in
for /etc/rsud/keys; the unit's own lines are then followed:

  LoadCredential=rsu.key:<sysconfdir>/rsud/keys/rsu.key
      systemd's part, done here: the key copied into a credentials directory readable by the service's
      user only (mode 0400 in a 0500 directory, as systemd makes it), $CREDENTIALS_DIRECTORY set and %d
      replaced by it.
  DynamicUser=yes, CapabilityBoundingSet=, NoNewPrivileges=yes, UMask=0077, Nice=
      an unprivileged uid of systemd's dynamic range with no groups and no capabilities (setpriv), at the
      unit's nice value (nice, as root: rsud runs at it).
  SystemCallFilter=, RestrictAddressFamilies=, MemoryDenyWriteExecute=
      installed with libseccomp (sandbox_exec) from the unit's own lines, the groups expanded by
      `systemd-analyze syscall-filter`; a system call outside them kills rsud (SIGSYS), as under systemd.
  ExecStartPre=, ExecStart=, ExecReload=, KillSignal=SIGTERM
      run as written (paths moved into the work folder): --check-config passes, rsud starts signed, takes
      a signed announcement from a vehicle key in the trust list, reloads on SIGHUP, exits 0 on SIGTERM.

And the failure the unit exists to avoid: the same uid started without the credential (the key read from
root's file) is refused with an error naming the file and "Permission denied".
Not emulated (needs systemd): ProtectSystem=, PrivateTmp= and the other namespaces; those are checked by
`systemd-analyze verify` and `systemd-analyze security --offline=true` (verify_unit.sh).
Exit 77 (skipped) when not root: making root-only files and switching to another uid need it.
"""
import argparse
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import sys
import tempfile

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..", "tools", "python"))
from rsu_processes import Children, free_udp_port, read_text, wait_for  # noqa: E402

SERVICE_UID = 61235  # in systemd's DynamicUser= range (61184-65519), owning nothing on this machine


def unit_lines(unit_path):
    """The unit's `Key=value` lines as (key, value) pairs, in order (a key may repeat)."""
    lines = []
    with open(unit_path) as f:
        for line in f:
            line = line.strip()
            if line and not line.startswith(("#", "[")) and "=" in line:
                key, value = line.split("=", 1)
                lines.append((key, value))
    return lines


def one(lines, key):
    values = [v for k, v in lines if k == key]
    assert len(values) == 1, "the unit has %d %s= lines, expected 1" % (len(values), key)
    return values[0]


def syscall_group(name, seen=None):
    """The system calls of a systemd group (@system-service), nested groups expanded."""
    seen = set() if seen is None else seen
    if name in seen:
        return set()
    seen.add(name)
    r = subprocess.run(["systemd-analyze", "syscall-filter", name], capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stdout + r.stderr
    calls = set()
    for line in r.stdout.splitlines()[1:]:
        word = line.strip()
        if not word or word.startswith("#"):
            continue
        calls |= syscall_group(word, seen) if word.startswith("@") else {word}
    return calls


def allowed_syscalls(lines):
    """What the unit's SystemCallFilter= lines leave allowed: the first (an allow list) minus every `~`
    list after it (systemd's rule for an allow list followed by deny lists)."""
    allowed = None
    for value in (v for k, v in lines if k == "SystemCallFilter"):
        deny = value.startswith("~")
        names = value.lstrip("~").split()
        calls = set().union(*(syscall_group(n) if n.startswith("@") else {n} for n in names))
        if allowed is None:
            assert not deny, "the unit's first SystemCallFilter= is a deny list: no allow list to check"
            allowed = calls
        elif deny:
            allowed -= calls
        else:
            allowed |= calls
    assert allowed, "the unit has no SystemCallFilter="
    return allowed


def family_numbers(lines):
    return ",".join(str(int(getattr(socket, name))) for name in one(lines, "RestrictAddressFamilies").split())


def unit_command(value, paths):
    """An Exec line of the unit with its installed paths and %d moved to this test's."""
    for installed, here in paths:
        value = value.replace(installed, here)
    return value.split()


def main():
    p = argparse.ArgumentParser()
    for name in ("unit", "sysconfdir", "sbindir", "config", "rsud", "keygen", "send", "sandbox_exec", "work"):
        p.add_argument("--" + name.replace("_", "-"), required=True)
    args = p.parse_args()
    if os.geteuid() != 0:
        print("SKIP: not root: making root-only key files and running rsud as another uid need root")
        return 77
    # The service's uid must reach rsud and its files. A checkout inside a directory closed to other users
    # (mktemp -d makes 0700) leaves the build tree unreachable: the work folder then goes under the system's
    # temporary directory, and the programs run as that uid are copied into it.
    work = args.work
    moved = not reachable_by_others(os.path.dirname(os.path.abspath(work)))
    if moved:
        work = tempfile.mkdtemp(prefix="rsud_as_unit.")
        print("NOTE: %s is not reachable by other users: working in %s" % (args.work, work))
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    os.chmod(work, 0o755)
    for name in ("rsud", "sandbox_exec"):
        program = getattr(args, name)
        if program != "none" and not reachable_by_others(os.path.dirname(os.path.abspath(program))):
            os.makedirs(os.path.join(work, "bin"), mode=0o755, exist_ok=True)
            copy = os.path.join(work, "bin", os.path.basename(program))
            shutil.copy2(program, copy)
            os.chmod(copy, 0o755)
            setattr(args, name, copy)
    assert reachable_by_others(work) and reachable_by_others(os.path.dirname(args.rsud))
    lines = unit_lines(args.unit)
    children = Children()
    try:
        result = run(args, work, lines, children)
    finally:
        children.kill_all()
    if moved and result == 0:
        shutil.rmtree(work, ignore_errors=True)
    return result


def reachable_by_others(directory):
    """Whether a user outside the owner's and group can enter the directory: every ancestor searchable."""
    path = os.path.abspath(directory)
    while True:
        if os.stat(path).st_mode & 0o001 == 0:
            return False
        parent = os.path.dirname(path)
        if parent == path:
            return True
        path = parent


def keygen(args, *words):
    r = subprocess.run([args.keygen] + list(words), capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stdout + r.stderr
    return r.stdout


def run(args, work, lines, children):
    etc = os.path.join(work, "etc")  # the unit's <sysconfdir>
    keys = os.path.join(etc, "rsud", "keys")
    # The README's commands (section "Running rsud as a service"), as root with root's umask.
    os.umask(0o022)
    keygen(args, os.path.join(keys, "rsu"))
    keygen(args, os.path.join(work, "car1"), "--trust-list", os.path.join(keys, "trust.list"), "--role", "vehicle",
           "--ids", "1")
    key = os.path.join(keys, "rsu.key")
    st = os.stat(key)
    assert st.st_uid == 0 and stat.S_IMODE(st.st_mode) == 0o600, "rsu.key: uid %d mode %o" % (st.st_uid, st.st_mode)
    for readable in (keys, os.path.join(keys, "trust.list"), os.path.join(keys, "rsu.pub")):
        assert os.stat(readable).st_mode & 0o004, "%s is not readable by rsud's user" % readable

    # The shipped configuration, its paths moved here, on loopback and free ports, a stats file in the
    # service's own state folder (StateDirectory=rsud: owned by its user).
    state = os.path.join(work, "state")
    os.makedirs(state)
    os.chown(state, SERVICE_UID, SERVICE_UID)
    v2i_port, lidar_port = free_udp_port(), free_udp_port()
    with open(args.config) as f:
        config = f.read()
    for old, new in (("/etc/rsud/", os.path.join(etc, "rsud") + "/"), ("0.0.0.0", "127.0.0.1"),
                     ("port: 4500", "port: %d" % v2i_port), ("port: 2368 ", "port: %d " % lidar_port),
                     ("stats_interval_s: 60.0", "stats_interval_s: 0.2"),
                     ("# stats_file: /run/rsud/stats", "stats_file: %s/stats" % state)):
        assert old in config, "the shipped configuration no longer has %r" % old
        config = config.replace(old, new)
    config_path = os.path.join(etc, "rsud", "rsud.yaml")
    with open(config_path, "w") as f:
        f.write(config)

    # LoadCredential=: the file it names is the one rsu-keygen made; systemd's copy for the service.
    credential = one(lines, "LoadCredential")
    name, source = credential.split(":", 1)
    assert source == os.path.join(args.sysconfdir, "rsud", "keys", "rsu.key"), credential
    credentials = os.path.join(work, "credentials", "rsud.service")
    os.makedirs(credentials)
    shutil.copyfile(os.path.join(keys, os.path.basename(source)), os.path.join(credentials, name))
    os.chmod(os.path.join(credentials, name), 0o400)
    os.chmod(credentials, 0o500)
    for path in (credentials, os.path.join(credentials, name)):
        os.chown(path, SERVICE_UID, SERVICE_UID)
    paths = [(os.path.join(args.sbindir, "rsud"), args.rsud), (args.sysconfdir + "/", etc + "/"), ("%d", credentials)]
    env = dict(os.environ, CREDENTIALS_DIRECTORY=credentials)

    # DynamicUser= etc.: the uid, no groups, no capabilities, no new privileges, UMask=.
    umask = one(lines, "UMask")
    # Nice=: systemd sets it before dropping privileges; here nice(1) as root does.
    as_service = ["nice", "-n", one(lines, "Nice"), "setpriv", "--reuid", str(SERVICE_UID), "--regid", str(SERVICE_UID), "--clear-groups",
                  "--inh-caps=-all", "--bounding-set=-all", "--no-new-privs", "sh", "-c", 'umask %s && exec "$@"' % umask,
                  "sh"]
    # SystemCallFilter= etc. through seccomp, when this machine can.
    sandbox = []
    if args.sandbox_exec == "none" or shutil.which("systemd-analyze") is None:
        print("NOTE: the unit's SystemCallFilter= is not applied: %s" % (
            "a sanitizer build, or libseccomp not found at build time" if args.sandbox_exec == "none"
            else "no systemd-analyze"))
    else:
        allowed = allowed_syscalls(lines)
        allow_file = os.path.join(work, "syscalls.allowed")
        with open(allow_file, "w") as f:
            f.write("\n".join(sorted(allowed)) + "\n")
        sandbox = [args.sandbox_exec, "--allow", allow_file, "--address-families", family_numbers(lines)]
        if one(lines, "MemoryDenyWriteExecute") == "yes":
            sandbox.append("--deny-write-execute")
        sandbox.append("--")
        # The filter bites: a call the unit denies (chroot, @privileged) kills the process.
        r = subprocess.run(as_service + sandbox + ["chroot", "/", "true"], capture_output=True, text=True, timeout=30)
        assert r.returncode == -signal.SIGSYS or r.returncode == 128 + signal.SIGSYS, (
            "chroot under the unit's filter: exit %d %s" % (r.returncode, r.stderr))
        print("ok: seccomp: %d system calls allowed (%s), chroot killed the process with SIGSYS" % (
            len(allowed), " ".join(v for k, v in lines if k == "SystemCallFilter")))

    # Without the credential: root's key file is closed to the service's user, and the error says why.
    r = subprocess.run(as_service + [args.rsud, "--check-config", "--config", config_path], capture_output=True,
                       text=True, timeout=30, env=env)
    assert r.returncode == 1, "rsud read root's key as uid %d: %s" % (SERVICE_UID, r.stdout + r.stderr)
    assert "security.key_file: %s:0: <file>: cannot open: Permission denied" % key in r.stderr, r.stdout + r.stderr
    print("ok: without the credential: %s" % (r.stdout + r.stderr).strip().splitlines()[-1])

    # ExecStartPre=: the configuration check, as the unit runs it.
    pre = unit_command(one(lines, "ExecStartPre"), paths)
    r = subprocess.run(as_service + sandbox + pre, capture_output=True, text=True, timeout=30, env=env)
    assert r.returncode == 0, "ExecStartPre %s: exit %d\n%s" % (pre, r.returncode, r.stdout + r.stderr)
    assert re.search(r"security signed: key [0-9a-f]+", r.stdout), r.stdout
    assert "readable by group" not in r.stdout, r.stdout

    # ExecStart=: rsud serves signed; a vehicle key from the trust list is accepted.
    start = unit_command(one(lines, "ExecStart"), paths)
    log = os.path.join(work, "rsud.log")
    rsud = children.spawn(as_service + sandbox + start, log, env=env)
    stats_path = os.path.join(state, "stats")

    def stats():
        values = {}
        for line in read_text(stats_path).splitlines() if os.path.exists(stats_path) else []:
            k, v = line.split()
            values[k] = float(v)
        return values

    wait_for(lambda: "learning the background" in read_text(log), 10, "rsud to start", watch=rsud, watch_log=log)
    r = subprocess.run([args.send, "--to", "127.0.0.1:%d" % v2i_port, "--kind", "announcement", "--id", "1", "--key",
                        os.path.join(work, "car1.key")], capture_output=True, text=True, timeout=30)
    assert r.returncode == 0, r.stdout + r.stderr
    wait_for(lambda: stats().get("auth.accepted", 0) >= 1, 5, "the signed announcement accepted", watch=rsud,
             watch_log=log)
    s = stats()
    assert s["security.insecure_mode"] == 0, s
    # Nice=: the process serving is rsud itself (every wrapper above execs), at the unit's nice value.
    nice = int(read_text("/proc/%d/stat" % rsud.pid).rsplit(")", 1)[1].split()[16])
    assert nice == int(one(lines, "Nice")), "rsud runs at nice %d, the unit says %s" % (nice, one(lines, "Nice"))
    # ExecReload=/bin/kill -HUP $MAINPID: the configuration and the credential read again.
    assert one(lines, "ExecReload") == "/bin/kill -HUP $MAINPID"
    rsud.send_signal(signal.SIGHUP)
    wait_for(lambda: "configuration reloaded" in read_text(log), 5, "the reload", watch=rsud, watch_log=log)
    assert one(lines, "KillSignal") == "SIGTERM"
    rsud.send_signal(signal.SIGTERM)
    rc = rsud.wait(timeout=10)
    assert rc == 0, "rsud exited %d on SIGTERM under the unit's sandbox:\n%s" % (rc, read_text(log)[-3000:])
    print("ok: rsud ran as uid %d with the unit's credential%s: check-config, start, a signed announcement "
          "accepted at nice %s, SIGHUP reload, SIGTERM exit 0" % (SERVICE_UID, " and seccomp filter" if sandbox else "",
                                                             one(lines, "Nice")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
