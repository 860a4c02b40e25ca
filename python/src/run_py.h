#pragma once
#include "common.h"

namespace rvlio::python {
void BindRun(py::module_& m);
}  // namespace rvlio::python
