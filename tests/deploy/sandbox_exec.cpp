// SPDX-License-Identifier: Apache-2.0
// sandbox_exec: runs a program under the seccomp filters a systemd unit's sandbox would install, for
// tests on a machine without systemd as PID 1 (tests/deploy/rsud_as_unit.py). With libseccomp, as systemd
// itself does it:
//   --allow FILE                 SystemCallFilter=: only the system calls named in FILE (one a line, as
//                                `systemd-analyze syscall-filter` expands the unit's groups); any other kills
//                                the process with SIGSYS (systemd's default action)
//   --address-families 2,10,1    RestrictAddressFamilies=: socket() of any other family fails EAFNOSUPPORT
//   --deny-write-execute         MemoryDenyWriteExecute=: mappings both writable and executable, and
//                                making memory executable, fail EPERM
// then execs the program. Sets no_new_privs (required for an unprivileged filter; the unit's
// NoNewPrivileges=yes). Exit 2 for bad usage, 1 when the filter cannot be installed.
#include <seccomp.h>
#include <sys/mman.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <set>
#include <string>
#include <vector>

namespace {

int usage() {
  std::fprintf(stderr,
               "usage: sandbox_exec [--allow FILE] [--address-families N,N,...] [--deny-write-execute] -- "
               "PROGRAM [ARGS...]\n");
  return 2;
}

bool check(int rc, const char* what) {
  if (rc < 0) {
    std::fprintf(stderr, "sandbox_exec: %s: %s\n", what, std::strerror(-rc));
    return false;
  }
  return true;
}

}  // namespace

int main(int argc, char** argv) {
  std::string allow_file;
  std::vector<int> families;
  bool deny_write_execute = false;
  int i = 1;
  for (; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") {
      ++i;
      break;
    }
    if (arg == "--allow" && i + 1 < argc) {
      allow_file = argv[++i];
    } else if (arg == "--address-families" && i + 1 < argc) {
      for (const char* p = argv[++i]; *p != '\0';) {
        char* end = nullptr;
        families.push_back(static_cast<int>(std::strtol(p, &end, 10)));
        if (end == p)
          return usage();
        p = *end == ',' ? end + 1 : end;
      }
    } else if (arg == "--deny-write-execute") {
      deny_write_execute = true;
    } else {
      return usage();
    }
  }
  if (i >= argc)
    return usage();

  scmp_filter_ctx ctx = seccomp_init(allow_file.empty() ? SCMP_ACT_ALLOW : SCMP_ACT_KILL_PROCESS);
  if (ctx == nullptr) {
    std::fprintf(stderr, "sandbox_exec: seccomp_init failed\n");
    return 1;
  }
  bool ok = true;
  if (!allow_file.empty()) {
    std::ifstream in(allow_file);
    if (!in) {
      std::fprintf(stderr, "sandbox_exec: %s: cannot open: %s\n", allow_file.c_str(), std::strerror(errno));
      return 1;
    }
    std::set<std::string> names;
    for (std::string line; std::getline(in, line);) {
      if (!line.empty() && line[0] != '#')
        names.insert(line);
    }
    for (const std::string& name : names) {
      const int nr = seccomp_syscall_resolve_name(name.c_str());
      if (nr == __NR_SCMP_ERROR)
        continue;  // a call of another architecture (the groups list them all); systemd skips them too
      ok = ok && check(seccomp_rule_add(ctx, SCMP_ACT_ALLOW, nr, 0), name.c_str());
    }
  }
  if (!families.empty()) {
    // Every family but the listed ones: the 64 below AF_MAX cover what Linux has.
    for (int family = 0; family < 64; ++family) {
      bool listed = false;
      for (const int f : families)
        listed = listed || f == family;
      if (!listed) {
        ok = ok && check(seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EAFNOSUPPORT), SCMP_SYS(socket), 1,
                                          SCMP_A0(SCMP_CMP_EQ, static_cast<scmp_datum_t>(family))),
                         "socket family rule");
      }
    }
  }
  if (deny_write_execute) {
    const scmp_datum_t wx = PROT_WRITE | PROT_EXEC;
    ok = ok && check(seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(mmap), 1,
                                      SCMP_A2(SCMP_CMP_MASKED_EQ, wx, wx)),
                     "mmap rule");
    ok = ok && check(seccomp_rule_add(ctx, SCMP_ACT_ERRNO(EPERM), SCMP_SYS(mprotect), 1,
                                      SCMP_A2(SCMP_CMP_MASKED_EQ, PROT_EXEC, PROT_EXEC)),
                     "mprotect rule");
  }
  ok = ok && check(seccomp_attr_set(ctx, SCMP_FLTATR_CTL_NNP, 1), "no_new_privs");
  ok = ok && check(seccomp_load(ctx), "seccomp_load");
  seccomp_release(ctx);
  if (!ok)
    return 1;
  execvp(argv[i], argv + i);
  std::fprintf(stderr, "sandbox_exec: cannot run %s: %s\n", argv[i], std::strerror(errno));
  return 127;
}
