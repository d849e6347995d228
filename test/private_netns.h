// Tests that start apps talking over udpm:// run inside a private network namespace that
// scripts/netns-run.sh makes (DEVELOPERS.md's network rule: multicast never leaves the machine).
// Their main() is main_in_private_netns, which re-executes the test binary through that script
// unless the process already sees no interface but lo.
#pragma once

#include <gtest/gtest.h>
#include <net/if.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

namespace fact::test {

// True when this process sees no network interface but lo: a private namespace. (if_nameindex asks
// the kernel about this process's namespace; /sys/class/net would show the host's.)
inline bool only_loopback() {
  struct if_nameindex* names = if_nameindex();
  if (names == nullptr) return false;
  bool only_lo = true;
  for (struct if_nameindex* i = names; i->if_index != 0; ++i)
    if (std::string(i->if_name) != "lo") only_lo = false;
  if_freenameindex(names);
  return only_lo;
}

// A test binary's main(): outside a private namespace it re-executes itself as
// `netns_run <this binary> <its arguments>` (exit 125 with the reason when that cannot start);
// inside one, or when it only lists its tests (ctest's discovery at build time), it runs them.
inline int main_in_private_netns(int argc, char** argv, const char* netns_run) {
  bool listing = false;
  for (int i = 1; i < argc; ++i)
    if (std::string(argv[i]).rfind("--gtest_list_tests", 0) == 0) listing = true;
  if (!listing && !only_loopback()) {
    std::vector<std::string> words = {netns_run, std::filesystem::read_symlink("/proc/self/exe").string()};
    for (int i = 1; i < argc; ++i) words.push_back(argv[i]);
    std::vector<char*> args;
    for (std::string& word : words) args.push_back(word.data());
    args.push_back(nullptr);
    execv(netns_run, args.data());
    std::fprintf(stderr, "cannot run %s: %s\n", netns_run, std::strerror(errno));
    return 125;
  }
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}

}  // namespace fact::test
