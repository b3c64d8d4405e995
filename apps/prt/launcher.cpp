// prt: a launcher that answers `prt --version` itself and hands every other command line, unchanged, to
// prt-driver next to it (the real driver, apps/prt/main.cpp). The driver links every stage's libraries, about 40
// shared libraries (OpenImageIO's ~260 are loaded only by stages that read or write an image, lib/image's
// image_library.h). The launcher links only the C library, so `prt --version` starts in a millisecond or two, and
// each other command pays one extra exec (well under a millisecond next to the driver's own start-up).
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <string>

#include <unistd.h>

int main(int argc, char** argv) {
    if (argc == 2 && std::strcmp(argv[1], "--version") == 0) {
        std::puts("prt " PRT_VERSION);
        return 0;
    }
    char self[4096];
    ssize_t length = readlink("/proc/self/exe", self, sizeof self - 1);
    if (length <= 0) {
        std::fprintf(stderr, "prt: cannot find its own executable: %s\n", std::strerror(errno));
        return 1;
    }
    std::string driver(self, size_t(length));
    driver = driver.substr(0, driver.rfind('/') + 1) + "prt-driver";
    execv(driver.c_str(), argv);
    std::fprintf(stderr, "prt: cannot run %s: %s\n", driver.c_str(), std::strerror(errno));
    return 1;
}
