// prt/status.h: how the runtime reports errors. Two ways, the same information:
//  - the throwing API (prt/relight.h, prt/hybrid.h, ...) throws prt::Error, a std::runtime_error whose what() is
//    "SOURCE: PLACE: PROBLEM" (catch std::exception; the class itself is lib/core's and is not installed);
//  - the no-throw API (prt/nothrow.h) returns a Status, or an Expected<T> holding a value or a Status, and never
//    throws, so an engine built with -fno-exceptions can call it. Every function there catches whatever the
//    library threw (std::bad_alloc included) and turns it into a code and the same message.
// std only: no logging, no process hooks.
#pragma once

#include <string>
#include <utility>

namespace prt {

enum class StatusCode {
    Ok = 0,
    NotFound,     // the file does not exist or cannot be opened
    Corrupt,      // the file exists but is not a valid bundle (truncated, bad checksum, malformed glTF or layers)
    InvalidInput, // the arguments do not meet the function's needs (a vertex range outside the model, ...)
    OutOfMemory,  // an allocation failed
    Internal,     // anything else
};

// The name of a code, for messages: "ok", "not found", "corrupt", "invalid input", "out of memory", "internal".
const char* statusName(StatusCode code) noexcept;

struct Status {
    StatusCode code = StatusCode::Ok;
    std::string message; // empty when ok; else "SOURCE: PLACE: PROBLEM", as prt::Error's what()
    bool ok() const noexcept { return code == StatusCode::Ok; }
    explicit operator bool() const noexcept { return ok(); }
};

// A value or the Status saying why there is none: std::expected in spirit, in C++17.
template <class T>
class Expected {
public:
    Expected(T value) : value_(std::move(value)) {}
    Expected(Status status) : status_(std::move(status)) {}
    bool ok() const noexcept { return status_.ok(); }
    explicit operator bool() const noexcept { return ok(); }
    const Status& status() const noexcept { return status_; }
    // Needs ok(); the value is default-constructed otherwise.
    T& value() & noexcept { return value_; }
    const T& value() const& noexcept { return value_; }
    T&& value() && noexcept { return std::move(value_); }

private:
    T value_{};
    Status status_;
};

} // namespace prt
