#pragma once

#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace deli::testing {

struct ShellResult {
  int status;          // the exit status, -1 when killed by a signal
  std::string output;  // stdout and stderr together
};

// Runs a command through /bin/sh as a user would, capturing what it prints.
inline ShellResult run_shell(const std::string& command) {
  ShellResult r{-1, ""};
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  if (!pipe) return r;
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) r.output += buffer;
  const int raw = pclose(pipe);
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  return r;
}

}  // namespace deli::testing
