#pragma once
#include "common.h"

namespace rvlio::python {
void BindBag(py::module_& m);
}  // namespace rvlio::python
