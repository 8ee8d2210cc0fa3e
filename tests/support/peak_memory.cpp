// at_peak_memory REPORT STDERR PROGRAM [ARG...]: runs PROGRAM (no shell) with its standard input
// and output on /dev/null and its standard error into the file STDERR, then writes
// "<exit status> <peak resident KiB>" to REPORT (the exit status as -N when signal N killed it).
//
// Why a program of its own: a child forked from a test process starts with a copy of that
// process's memory map, and Linux keeps the copy's resident size in the child's ru_maxrss across
// exec. A test process that holds a few hundred MB (the whole suite run in one process) would make
// every program it measures look that big. Forked from this small process instead, the program's
// peak is its own.
#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>

int main(int argc, char** argv) {
  if (argc < 4) {
    std::fprintf(stderr, "usage: at_peak_memory REPORT STDERR PROGRAM [ARG...]\n");
    return 2;
  }
  const pid_t pid = ::fork();
  if (pid < 0) {
    std::perror("at_peak_memory: fork");
    return 2;
  }
  if (pid == 0) {
    const int err = ::open(argv[2], O_WRONLY | O_CREAT | O_TRUNC, 0644);
    const int null = ::open("/dev/null", O_RDWR);
    if (err < 0 || null < 0) ::_exit(126);
    ::dup2(null, 0);
    ::dup2(null, 1);
    ::dup2(err, 2);
    ::execv(argv[3], argv + 3);
    ::_exit(127);
  }
  int status = 0;
  rusage usage{};
  while (::wait4(pid, &status, 0, &usage) < 0) {
    if (errno != EINTR) {
      std::perror("at_peak_memory: wait4");
      return 2;
    }
  }
  std::FILE* report = std::fopen(argv[1], "w");
  if (!report) {
    std::perror(argv[1]);
    return 2;
  }
  const int exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
  std::fprintf(report, "%d %ld\n", exitCode, usage.ru_maxrss);
  return std::fclose(report) == 0 ? 0 : 2;
}
