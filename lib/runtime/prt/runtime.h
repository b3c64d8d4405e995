// prt/runtime.h: the whole thin runtime, one include. Each feature has its own header, documented there:
//   prt/relight.h   per-vertex relighting, RelightModel and its loaders
//   prt/adaptive.h  adaptive, quantised and clustered-PCA transfer (`prt adapt`)
//   prt/texels.h    per-texel transfer (`prt bake`)
//   prt/lighting.h  SH lighting: prt-sh JSON, environment maps, rotation
//   prt/hybrid.h    cone lights plus an SH residual (`prt envlight`)
//   prt/fiv.h       shadows of moving occluders (`prt fiv`)
//   prt/glossy.h    glossy lobes (`prt glossy`)
//   prt/jobs.h      the job-system hook (the runtime starts no threads)
//   prt/status.h    errors: prt::Error, status codes
//   prt/nothrow.h   the same API without exceptions
// bundle.h (the bundle reader and writer) and sh.h come along for the types these take.
#pragma once

#include "adaptive.h"
#include "bundle.h"
#include "fiv.h"
#include "glossy.h"
#include "hybrid.h"
#include "jobs.h"
#include "lighting.h"
#include "nothrow.h"
#include "relight.h"
#include "sh.h"
#include "status.h"
#include "texels.h"
