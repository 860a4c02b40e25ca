#include "rvlio/version.h"

namespace rvlio {

const char* LibraryVersion() { return RVLIO_VERSION; }

}  // namespace rvlio
