// In-repo forwarding header: the installed runtime's umbrella (prt/runtime.h, which an engine includes as
// <prt/runtime.h>) plus lib/core's core.h, which code inside prt uses alongside it (prt::Error, logging). Not
// installed; the runtime's own headers never include core.h.
#pragma once

#include "core.h"
#include "prt/runtime.h"
