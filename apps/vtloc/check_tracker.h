#pragma once
// `vtloc check --tracker`: the multi-touch filter on this device against its CPU reference.
#include "apps/vtloc/cli.h"

namespace vtloc::cli {

int tracker_check(Session& s, const Args& a);

}  // namespace vtloc::cli
