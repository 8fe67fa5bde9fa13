/**
 * \file bt_robot.c
 * The HCI build of the whole firmware on the host (hal/sim and the tests' world), its UART wired to a Bluetooth
 * controller reached as H4 over TCP, in real time: `bt_robot PORT SECONDS`. tests/bt_e2e.py --firmware runs it
 * against Bumble's virtual controllers and talks the PocketBot protocol to it over RFCOMM and the framed channel.
 */
#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#include "core/data.h"
#include "world.h"

static uint64_t now_us(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

int main(int argc, char **argv)
{
    if (argc != 3) {
        fprintf(stderr, "usage: bt_robot PORT SECONDS\n");
        return 2;
    }
    int s = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)atoi(argv[1]));
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (s < 0 || connect(s, (struct sockaddr *)&a, sizeof a) != 0) {
        perror("connect");
        return 1;
    }
    int one = 1;
    setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fcntl(s, F_SETFL, O_NONBLOCK);
    world_reset(7);
    world.link_bytes_per_ms = 0; /* the UART is the controller's, not the world's host */
    uint64_t start = now_us(), next = start, end = start + (uint64_t)atoi(argv[2]) * 1000000u;
    static uint8_t in[8192]; /* what the controller sent, fed to the UART at its baud rate */
    size_t in_len = 0, in_pos = 0;
    while (now_us() < end) {
        if (in_pos == in_len)
            in_pos = in_len = 0;
        ssize_t n = in_len < sizeof in ? read(s, in + in_len, sizeof in - in_len) : -1;
        if (n == 0)
            break;
        if (n > 0)
            in_len += (size_t)n;
        else if (errno != EAGAIN && in_len < sizeof in)
            break;
        if (now_us() < next) {
            usleep(100);
            continue;
        }
        next += 1000;
        for (int k = 0; k < 12 && in_pos < in_len; k++) /* 115200 Bd: about 12 bytes per ms each way */
            host_send_raw(&in[in_pos++], 1);
        world_run_ms(1);
        int32_t m = sim_uart_tx_take(12);
        if (m > 0 && write(s, sim_host_tx_buffer(), (size_t)m) != m)
            break;
    }
    close(s);
    printf("robot: wire %u timeouts %u resets %u dropped %u tx_dropped %u\n", robot_state.errors.bt_wire,
           robot_state.errors.bt_timeouts, robot_state.errors.bt_resets, robot_state.errors.bt_dropped,
           robot_state.errors.tx_dropped);
    return 0;
}
