// A cached `prt run` and `--plan` start no process (the cache keys are computed in process), and the stat-keyed
// hash memo they rely on is defeated by every change of content.
#include "pipeline_test_util.h"

#include <cerrno>
#include <chrono>
#include <cstddef>
#include <fcntl.h>
#include <linux/audit.h>
#include <linux/filter.h>
#include <linux/seccomp.h>
#include <sched.h>
#include <sys/prctl.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

namespace prt {
namespace {

#if defined(__x86_64__)
// Forbids every way of creating a process from here on, across exec: fork, vfork, and clone without
// CLONE_THREAD fail with EPERM; clone3, whose flags a filter cannot read, fails with ENOSYS, so that glibc falls
// back to clone (threads still start; posix_spawn, popen and fork do not). exec is allowed: it starts no process.
bool forbidNewProcesses() {
    struct sock_filter filter[] = {
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, arch)),           // 0
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, AUDIT_ARCH_X86_64, 1, 0),                      // 1
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),                                      // 2
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, nr)),             // 3
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_clone3, 0, 1),                            // 4
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | ENOSYS),                             // 5
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_fork, 4, 0),                              // 6 -> 11
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_vfork, 3, 0),                             // 7 -> 11
        BPF_JUMP(BPF_JMP | BPF_JEQ | BPF_K, __NR_clone, 0, 3),                             // 8 -> 9 | 12
        BPF_STMT(BPF_LD | BPF_W | BPF_ABS, offsetof(struct seccomp_data, args[0])),        // 9: flags, low word
        BPF_JUMP(BPF_JMP | BPF_JSET | BPF_K, CLONE_THREAD, 1, 0),                          // 10 -> 12 | 11
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ERRNO | EPERM),                              // 11
        BPF_STMT(BPF_RET | BPF_K, SECCOMP_RET_ALLOW),                                      // 12
    };
    struct sock_fprog program = {static_cast<unsigned short>(sizeof(filter) / sizeof(filter[0])), filter};
    return prctl(PR_SET_NO_NEW_PRIVS, 1, 0, 0, 0) == 0 && prctl(PR_SET_SECCOMP, SECCOMP_MODE_FILTER, &program) == 0;
}

// Runs `prt ARGS` with process creation forbidden; its stdout and stderr go to `log`. Returns its exit status.
int runWithoutProcesses(const std::vector<std::string>& args, const std::string& log) {
    std::vector<std::string> words = {test::kPrt};
    words.insert(words.end(), args.begin(), args.end());
    std::vector<char*> argv;
    for (std::string& word : words) argv.push_back(word.data());
    argv.push_back(nullptr);
    pid_t pid = fork();
    if (pid == 0) {
        int fd = open(log.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (fd < 0 || dup2(fd, 1) < 0 || dup2(fd, 2) < 0 || !forbidNewProcesses()) _exit(120);
        execv(argv[0], argv.data());
        _exit(121);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

TEST(NoProcess, TheFilterStopsForkAndPopenButNotThreads) {
    pid_t pid = fork();
    if (pid == 0) {
        if (!forbidNewProcesses()) _exit(10);
        int ran = 0;
        std::thread([&] { ran = 1; }).join();
        if (ran != 1) _exit(11);
        if (fork() >= 0) _exit(12);
        std::FILE* pipe = popen("true", "r");
        if (pipe && pclose(pipe) == 0) _exit(13);
        _exit(0);
    }
    int status = 0;
    waitpid(pid, &status, 0);
    ASSERT_TRUE(WIFEXITED(status));
    EXPECT_EQ(WEXITSTATUS(status), 0) << "10: no filter, 11: no thread, 12: fork ran, 13: popen ran";
}

// The cached rerun and the plan run with process creation forbidden, and succeed: nothing was started to
// compute a key. The same run with --force fails there (its stages are processes): the filter does bite.
TEST(NoProcess, CachedRunAndPlanStartNoProcess) {
    test::TempDir dir;
    test::writeSkyExr(dir / "sky.exr", 1.0f);
    test::writeText(dir / "p.toml", test::twoSpheresPipeline(dir.path, 16, 1, dir / "out"));
    std::string cache = dir / "cache";
    std::string output;
    ASSERT_EQ(test::shell(test::kPrt + " --quiet run " + dir / "p.toml" + " --cache-dir " + cache + " --threads 2", &output), 0)
        << output;

    EXPECT_EQ(runWithoutProcesses({"--quiet", "run", dir / "p.toml", "--cache-dir", cache}, dir / "cached.log"), 0)
        << readFileBytes(dir / "cached.log");
    EXPECT_EQ(runWithoutProcesses({"run", dir / "p.toml", "--cache-dir", cache, "--plan"}, dir / "plan.log"), 0)
        << readFileBytes(dir / "plan.log");
    std::string plan = readFileBytes(dir / "plan.log");
    EXPECT_NE(plan.find("3 stages, 0 to run"), std::string::npos) << plan;
    EXPECT_NE(runWithoutProcesses({"--quiet", "run", dir / "p.toml", "--cache-dir", cache, "--force"}, dir / "forced.log"), 0)
        << readFileBytes(dir / "forced.log");
}
#endif

// ---- the hash memo ----

struct stat statOf(const std::string& path) {
    struct stat s {};
    EXPECT_EQ(::stat(path.c_str(), &s), 0);
    return s;
}

void setMtime(const std::string& path, const struct timespec& mtime) {
    struct timespec times[2] = {mtime, mtime};
    ASSERT_EQ(utimensat(AT_FDCWD, path.c_str(), times, 0), 0);
}

// A memo file claiming `hash` for `path` as it stands now (what an earlier run would have written).
void forgeMemo(const std::string& memo, const std::string& path, const std::string& hash) {
    struct stat s = statOf(path);
    nlohmann::json entry = {{"size", int64_t(s.st_size)},
                            {"mtime_ns", int64_t(s.st_mtim.tv_sec) * 1000000000 + s.st_mtim.tv_nsec},
                            {"ctime_ns", int64_t(s.st_ctim.tv_sec) * 1000000000 + s.st_ctim.tv_nsec},
                            {"inode", uint64_t(s.st_ino)}, {"device", uint64_t(s.st_dev)}, {"hash", hash},
                            {"hashed_at", 0}};
    test::writeText(memo, nlohmann::json({{std::filesystem::absolute(path).lexically_normal().string(), entry}}).dump());
}

const std::string kFake = "xxh128:00000000000000000000000000000001";

// An entry whose six stat fields match is used without reading the file (the forged hash comes back); once the
// file is rewritten with the same size and the same mtime restored, its ctime differs and the real hash is taken.
TEST(HashMemo, ARewriteWithTheSameSizeAndMtimeIsHashedAgain) {
    test::TempDir dir;
    std::string file = dir / "input.bin";
    test::writeText(file, "abcdefgh");
    struct timespec old = {1'000'000'000, 5}; // 2001: far older than the racy window
    setMtime(file, old);
    forgeMemo(dir / "memo-1.json", file, kFake);
    EXPECT_EQ(hashFileMemo(file, dir / "memo-1.json"), kFake);

    std::this_thread::sleep_for(std::chrono::milliseconds(20)); // a later ctime whatever the timestamp tick
    test::writeText(file, "abcdefgX");
    setMtime(file, old);
    EXPECT_EQ(statOf(file).st_size, 8);
    EXPECT_EQ(hashFileMemo(file, dir / "memo-1.json"), hashBytes("abcdefgX", 8));
}

TEST(HashMemo, ASameSizeRewriteWithAnMtimeChangeGetsANewHash) {
    test::TempDir dir;
    std::string file = dir / "input.bin";
    test::writeText(file, "12345678");
    forgeMemo(dir / "memo-2.json", file, kFake);
    EXPECT_EQ(hashFileMemo(file, dir / "memo-2.json"), kFake);
    test::writeText(file, "87654321");
    setMtime(file, {2'000'000'000, 0});
    EXPECT_EQ(hashFileMemo(file, dir / "memo-2.json"), hashBytes("87654321", 8));
}

// A file hashed within the racy window (just written) is not recorded, so that a write in the same timestamp
// tick cannot hide behind it; an older one is, and the memo file then holds its hash.
TEST(HashMemo, RecordsOnlyFilesOlderThanTheRacyWindow) {
    test::TempDir dir;
    std::string fresh = dir / "fresh.bin", settled = dir / "settled.bin", memo = dir / "memo-3.json";
    test::writeText(settled, "settled");
    test::writeText(fresh, "fresh");
    std::this_thread::sleep_for(std::chrono::milliseconds(2100)); // past the 2 s window for ctime too
    test::writeText(fresh, "fresh!");
    EXPECT_EQ(hashFileMemo(fresh, memo), hashBytes("fresh!", 6));
    EXPECT_EQ(hashFileMemo(settled, memo), hashBytes("settled", 7));
    nlohmann::json recorded = nlohmann::json::parse(readFileBytes(memo));
    EXPECT_FALSE(recorded.contains(std::filesystem::absolute(fresh).lexically_normal().string()));
    EXPECT_EQ(recorded[std::filesystem::absolute(settled).lexically_normal().string()]["hash"], hashBytes("settled", 7));
}

} // namespace
} // namespace prt
