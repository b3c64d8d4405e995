// The pipeline cache key's questions about prt, answered in process (apps/cli/build_info.cpp): `prt run` resolves
// every stage's options and the build's identity here instead of starting prt again.
#pragma once

#include <nlohmann/json.hpp>

#include <functional>
#include <string>
#include <vector>

namespace prt::cli {

// What a pipeline cache key holds about a prt build (`prt --build-info`): its version, build type, compiler, the
// content hash of `driver` (the prt-driver executable the stages run as; hashFileMemo in `memoFile`, "" for none),
// the versions of the libraries it was compiled against, and the real file name and size of each library the
// driver links, from the list its link step wrote to DRIVER.libs. The same answer in any process that asks.
// Throws prt::Error when the driver or its list cannot be read.
nlohmann::json buildInfo(const std::string& driver, const std::string& memoFile);

// Writes the libraries mapped into this process before main (what the executable links) to `path` as a JSON list
// of paths: the driver's link step runs it (`prt-driver --write-linked-libraries DRIVER.libs`).
void writeLinkedLibraries(const std::string& path);

// The prt-driver next to `program` (the `prt` launcher, a standalone prt-NAME, or the driver itself).
std::string driverOf(const std::string& program);

// RunOptions::askPrt for `prt run`: answers {PRT, "--build-info"} by buildInfo(driverOf(PRT), memoFile) and
// {PRT, "--resolved-options", STAGE, ...} with this process's own option definitions (runDriver with `answer`),
// never starting a process. Throws prt::Error for a question it cannot answer.
std::function<nlohmann::json(const std::vector<std::string>&)> inProcessAnswers(const std::string& memoFile);

} // namespace prt::cli
