// sandbox_exec CMD [ARGS...]: runs CMD under the seccomp rules systemd 252
// (Debian 12, src/shared/seccomp-util.c) installs for two options of
// deploy/systemd/luxeld.service, so deploy_sandbox can run PoCL and luxeld
// under them without a systemd to start the unit:
//   MemoryDenyWriteExecute=yes: mmap with both PROT_WRITE and PROT_EXEC, and
//     mprotect/pkey_mprotect adding PROT_EXEC, fail with EPERM (systemd also
//     filters shmat(SHM_EXEC); nothing here uses SysV shm);
//   RestrictAddressFamilies=AF_UNIX AF_INET AF_INET6: socket() of any other
//     family fails with EAFNOSUPPORT.
#include <errno.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <stddef.h>
#include <stdio.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/syscall.h>
#include <unistd.h>

#define ARG0 (offsetof(struct seccomp_data, args))
#define ARG2 (offsetof(struct seccomp_data, args) + 2 * sizeof(__u64))
#define DENY BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM)
#define ALLOW BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW)
enum { kProtWrite = 2, kProtExec = 4 };

int main(int argc, char** argv) {
  if (argc < 2) {
    fprintf(stderr, "usage: sandbox_exec CMD [ARGS...]\n");
    return 2;
  }
  struct sock_filter filter[] = {
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, nr)),
      // [1] socket: only AF_UNIX, AF_INET, AF_INET6; other calls go to [8]
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_socket, 0, 6),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, ARG0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AF_UNIX, 2, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AF_INET, 1, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AF_INET6, 0, 1),
      ALLOW,
      BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EAFNOSUPPORT),
      // [8] mmap: deny when (prot & (W|X)) == W|X; other calls go to [14]
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_mmap, 0, 5),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, ARG2),
      BPF_STMT(BPF_ALU | BPF_AND | BPF_K, kProtWrite | kProtExec),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, kProtWrite | kProtExec, 0, 1),
      DENY,
      ALLOW,
      // [14] mprotect, pkey_mprotect: deny when prot & X
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_mprotect, 1, 0),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_pkey_mprotect, 0, 4),
      BPF_STMT(BPF_LD | BPF_W | BPF_ABS, ARG2),
      BPF_STMT(BPF_ALU | BPF_AND | BPF_K, kProtExec),
      BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, 0, 1, 0),
      DENY,
      ALLOW,
  };
  struct sock_fprog prog = {sizeof(filter) / sizeof(filter[0]), filter};
  if (prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) != 0 ||
      prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &prog) != 0) {
    perror("sandbox_exec: seccomp");
    return 125;
  }
  execvp(argv[1], argv + 1);
  perror("sandbox_exec: exec");
  return 127;
}
