#include "socket_drops.hpp"

#include <dirent.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace motormix::node {

namespace {

// Inodes of this process's sockets ("socket:[12345]" links in /proc/self/fd).
std::vector<unsigned long> own_socket_inodes() {
  std::vector<unsigned long> inodes;
  DIR* dir = opendir("/proc/self/fd");
  if (dir == nullptr) return inodes;
  while (const dirent* entry = readdir(dir)) {
    if (entry->d_name[0] == '.') continue;
    const std::string path = std::string("/proc/self/fd/") + entry->d_name;
    char target[64] = {};
    const ssize_t n = readlink(path.c_str(), target, sizeof target - 1);
    unsigned long inode = 0;
    if (n > 0 && std::sscanf(target, "socket:[%lu]", &inode) == 1) inodes.push_back(inode);
  }
  closedir(dir);
  return inodes;
}

// Adds the drops of the rows of one table whose inode is ours; false when
// the table cannot be read.
bool add_drops(const char* table, const std::vector<unsigned long>& inodes, std::int64_t& drops,
               bool& found) {
  std::ifstream in(table);
  if (!in) return false;
  std::string line;
  std::getline(in, line);  // header
  // sl local rem st tx:rx tr:tm retrnsmt uid timeout inode ref pointer drops
  while (std::getline(in, line)) {
    std::istringstream row(line);
    std::string skip;
    unsigned long inode = 0;
    long long ref = 0;
    std::string pointer;
    long long row_drops = 0;
    for (int i = 0; i < 9; ++i) row >> skip;
    if (!(row >> inode >> ref >> pointer >> row_drops)) continue;
    for (unsigned long mine : inodes) {
      if (mine == inode) {
        drops += row_drops;
        found = true;
      }
    }
  }
  return true;
}

}  // namespace

std::int64_t own_udp_socket_drops() {
  // Looked up every time: LCM opens its receive socket on the first
  // subscription, after a reader may have started.
  const std::vector<unsigned long> inodes = own_socket_inodes();
  if (inodes.empty()) return -1;
  std::int64_t drops = 0;
  bool found = false;
  const bool v4 = add_drops("/proc/net/udp", inodes, drops, found);
  const bool v6 = add_drops("/proc/net/udp6", inodes, drops, found);
  return (v4 || v6) && found ? drops : -1;
}

SocketDropsWatcher::SocketDropsWatcher()
    : thread_([this] {
        std::unique_lock<std::mutex> lock(mutex_);
        while (!stop_) {
          lock.unlock();
          latest_.store(own_udp_socket_drops(), std::memory_order_relaxed);
          lock.lock();
          wake_.wait_for(lock, std::chrono::seconds(1), [this] { return stop_; });
        }
      }) {}

SocketDropsWatcher::~SocketDropsWatcher() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_all();
  thread_.join();
}

}  // namespace motormix::node
