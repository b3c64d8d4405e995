// Silences OpenMesh's own log streams for a scope (lib/mesh internal): the stage's log is the only voice on
// stderr, and every failure OpenMesh would print is detected and reported as prt::Error instead.
#pragma once

#include <OpenMesh/Core/System/omstream.hh>

namespace prt::detail {

class QuietOpenMesh {
public:
    QuietOpenMesh() : log_(omlog().is_enabled()), out_(omout().is_enabled()), err_(omerr().is_enabled()) {
        omlog().disable();
        omout().disable();
        omerr().disable();
    }
    ~QuietOpenMesh() {
        if (log_) omlog().enable();
        if (out_) omout().enable();
        if (err_) omerr().enable();
    }
    QuietOpenMesh(const QuietOpenMesh&) = delete;
    QuietOpenMesh& operator=(const QuietOpenMesh&) = delete;

private:
    bool log_, out_, err_;
};

} // namespace prt::detail
