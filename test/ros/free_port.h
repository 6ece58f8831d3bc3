// A TCP port free on this machine now, for a test's private ROS master: a fixed port collides with a
// second suite running on the same machine (a clean-clone CI beside a developer's run), and rosnode then
// answers from the other suite's master.
#pragma once

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <unistd.h>

#include <stdexcept>

namespace go_feap::test {

/// The port the kernel gives a socket bound to 127.0.0.1:0, released before returning (the master takes
/// it a moment later; the kernel hands out ephemeral ports in turn, so another taker in between is unlikely).
inline int freeTcpPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) throw std::runtime_error("freeTcpPort: socket() failed");
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = 0;
  socklen_t length = sizeof(address);
  const bool ok = ::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof(address)) == 0 &&
                  ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) == 0;
  ::close(fd);
  if (!ok) throw std::runtime_error("freeTcpPort: no port could be bound on 127.0.0.1");
  return ntohs(address.sin_port);
}

}  // namespace go_feap::test
