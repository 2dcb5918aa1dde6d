// SPDX-License-Identifier: MIT
// The board image alone in a native harness library (firmware idle loop, no
// plant, no Python), for bench_rtl_loop.py: clocks per CPU second, and a
// process small enough to run under callgrind for instruction counts.
//   board_alone <libtlcosim.so> <clocks>
#include <dlfcn.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <ctime>

int main(int argc, char **argv)
{
    if (argc != 3) {
        std::fprintf(stderr, "usage: board_alone <libtlcosim.so> <clocks>\n");
        return 2;
    }
    void *lib = dlopen(argv[1], RTLD_NOW);
    if (!lib) {
        std::fprintf(stderr, "board_alone: %s\n", dlerror());
        return 2;
    }
    auto create = (void *(*)(void))dlsym(lib, "tl_create");
    auto destroy = (void (*)(void *))dlsym(lib, "tl_destroy");
    auto set_board = (void (*)(void *, int, int, int, int))dlsym(lib, "tl_set_board");
    auto run = (int (*)(void *, uint64_t, int))dlsym(lib, "tl_run");
    uint64_t n = std::strtoull(argv[2], nullptr, 0);
    void *h = create();
    set_board(h, 0, 1, 0, 0);   // reset, then released with the drives armed
    run(h, 20, 0);
    set_board(h, 1, 1, 1, 0);
    run(h, 200000, 0);          // past the firmware's start-up
    std::clock_t c0 = std::clock();
    run(h, 200000 + n, 0);
    double dt = double(std::clock() - c0) / CLOCKS_PER_SEC;
    std::printf("%.0f\n", n / dt);
    destroy(h);
    return 0;
}
