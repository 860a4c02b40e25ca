#pragma once
#include "common.h"

namespace rvlio::python {
void BindCompare(py::module_& m);
}  // namespace rvlio::python
