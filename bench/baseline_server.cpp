// dg-baseline: the reference Modbus TCP server, written only with libmodbus's own server API in
// the shape of its examples: one thread, select() over the listening socket and every client,
// modbus_receive + modbus_reply on a modbus_mapping_t. Nothing here is tuned either way.
//
// The mapping has 141 holding registers (FC03 16..140, the benchmark's large read, works) and
// --inputs input registers (default 129, so FC04 0..18, the common block, and FC04 32..128,
// unicla-edrive's point range, both work), filled with a counting pattern. Accepted sockets get TCP_NODELAY, as drivegate's do.
#include <errno.h>
#include <modbus/modbus.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <sys/select.h>
#include <sys/socket.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

// FC03 of 125 (the maximum quantity, Application Protocol 6.3) from address 16, as drivegate
// serves it from the ed3100 parameters.
constexpr int kHoldingRegisters = 16 + 125;

volatile std::sig_atomic_t g_stop = 0;  // signal handler flag: the one global this tool needs
void on_signal(int) {
  g_stop = 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::string host = "127.0.0.1";
  int port = 1503;
  int inputs = 129;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string k = argv[i];
    if (k == "--host")
      host = argv[i + 1];
    else if (k == "--port")
      port = std::atoi(argv[i + 1]);
    else if (k == "--inputs")
      inputs = std::atoi(argv[i + 1]);
    else {
      std::fprintf(stderr, "usage: dg-baseline [--host H] [--port P] [--inputs N]\n");
      return 2;
    }
  }
  std::signal(SIGINT, on_signal);
  std::signal(SIGTERM, on_signal);

  modbus_t* ctx = modbus_new_tcp(host.c_str(), port);
  modbus_mapping_t* map = modbus_mapping_new(0, 0, kHoldingRegisters, inputs);
  if (ctx == nullptr || map == nullptr) {
    std::fprintf(stderr, "dg-baseline: %s\n", modbus_strerror(errno));
    return 1;
  }
  for (int i = 0; i < kHoldingRegisters; ++i) map->tab_registers[i] = static_cast<uint16_t>(i);
  for (int i = 0; i < inputs; ++i) map->tab_input_registers[i] = static_cast<uint16_t>(1000 + i);

  const int server = modbus_tcp_listen(ctx, 1024);
  if (server < 0) {
    std::fprintf(stderr, "dg-baseline: listen: %s\n", modbus_strerror(errno));
    return 1;
  }
  std::printf("listening on %s:%d\n", host.c_str(), port);
  std::fflush(stdout);

  fd_set all;
  FD_ZERO(&all);
  FD_SET(server, &all);
  int max_fd = server;
  uint8_t query[MODBUS_TCP_MAX_ADU_LENGTH];
  while (g_stop == 0) {
    fd_set ready = all;
    if (select(max_fd + 1, &ready, nullptr, nullptr, nullptr) < 0) {
      if (errno == EINTR) continue;
      std::perror("dg-baseline: select");
      break;
    }
    for (int fd = 0; fd <= max_fd; ++fd) {
      if (!FD_ISSET(fd, &ready)) continue;
      if (fd == server) {
        sockaddr_storage peer{};
        socklen_t len = sizeof peer;
        const int client = accept(server, reinterpret_cast<sockaddr*>(&peer), &len);
        if (client < 0) continue;
        const int one = 1;
        setsockopt(client, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
        FD_SET(client, &all);
        if (client > max_fd) max_fd = client;
        continue;
      }
      modbus_set_socket(ctx, fd);
      const int rc = modbus_receive(ctx, query);
      if (rc > 0) {
        modbus_reply(ctx, query, rc, map);
      } else if (rc == -1) {
        close(fd);
        FD_CLR(fd, &all);
        if (fd == max_fd) {
          while (max_fd > server && !FD_ISSET(max_fd, &all)) --max_fd;
        }
      }
    }
  }
  close(server);
  modbus_mapping_free(map);
  modbus_free(ctx);
  return 0;
}
