#include "bt_live.h"

#include <arpa/inet.h>
#include <errno.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <stdio.h>
#include <sys/socket.h>
#include <time.h>
#include <unistd.h>

#define WIRE_BYTES_PER_MS 12

static uint64_t now_us(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (uint64_t)t.tv_sec * 1000000u + (uint64_t)t.tv_nsec / 1000u;
}

int bt_live_run(int port, int seconds, const bt_live_robot_t *robot)
{
    int s = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in a = {0};
    a.sin_family = AF_INET;
    a.sin_port = htons((uint16_t)port);
    a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    if (s < 0 || connect(s, (struct sockaddr *)&a, sizeof a) != 0) {
        perror("connect");
        return 1;
    }
    int one = 1;
    setsockopt(s, IPPROTO_TCP, TCP_NODELAY, &one, sizeof one);
    fcntl(s, F_SETFL, O_NONBLOCK);
    static uint8_t in[8192]; /* what the controller sent, fed to the UART at the wire's pace */
    size_t in_len = 0, in_pos = 0;
    uint64_t next = now_us(), end = next + (uint64_t)seconds * 1000000u;
    while (now_us() < end) {
        if (in_pos == in_len)
            in_pos = in_len = 0;
        ssize_t n = in_len < sizeof in ? read(s, in + in_len, sizeof in - in_len) : -1;
        if (n == 0)
            break; /* the controller went away */
        if (n > 0)
            in_len += (size_t)n;
        else if (errno != EAGAIN && in_len < sizeof in)
            break;
        if (now_us() < next) {
            usleep(100);
            continue;
        }
        next += 1000;
        size_t k = in_len - in_pos > WIRE_BYTES_PER_MS ? WIRE_BYTES_PER_MS : in_len - in_pos;
        robot->rx(in + in_pos, (uint16_t)k);
        in_pos += k;
        robot->tick();
        uint8_t out[WIRE_BYTES_PER_MS];
        int m = robot->tx(out, WIRE_BYTES_PER_MS);
        if (m > 0 && write(s, out, (size_t)m) != m)
            break;
    }
    close(s);
    return 0;
}
