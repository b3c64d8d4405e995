// Shared by the libFuzzer harnesses: each reader is fed the fuzzer's bytes as a file, and may only succeed or
// throw prt::Error (exit 3 and friends). Any other exception, a sanitizer report or a crash is a finding.
#pragma once

#include "core.h"

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <string>
#include <unistd.h>

namespace prt::fuzz {

// A private folder per process, so external URIs of a fuzzed glTF can only name files the harness wrote.
inline const std::string& folder() {
    static const std::string path = [] {
        std::string dir = (std::filesystem::temp_directory_path() / ("prt-fuzz-" + std::to_string(getpid()))).string();
        std::filesystem::create_directories(dir);
        return dir;
    }();
    return path;
}

// Writes `data` to FOLDER/input.EXTENSION and returns the path.
inline std::string writeInput(const uint8_t* data, size_t size, const std::string& extension) {
    std::string path = folder() + "/input." + extension;
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) std::abort();
    if (size > 0 && std::fwrite(data, 1, size, file) != size) std::abort();
    std::fclose(file);
    return path;
}

// Runs `read`; prt::Error is the expected outcome for bad input. Anything else escapes to libFuzzer.
inline void expectOnlyErrors(const std::function<void()>& read) {
    try {
        read();
    } catch (const prt::Error& e) {
        if (e.exitCode() == kExitFailure) std::abort(); // hostile input must never read as an internal error
    }
}

// Keeps a fuzzed file from claiming more than a fuzzer's memory limit before the reader refuses it.
inline void capElements() { setenv("PRT_MAX_ELEMENTS", "4000000", 0); }

} // namespace prt::fuzz
