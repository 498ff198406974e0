// The status page. A placeholder until the page lands: the JSON it reads is served already.
#include "routes.h"

namespace drivegate::http {

std::string_view status_page() {
  return R"(<!doctype html><html lang="en"><head><meta charset="utf-8"><title>drivegate</title></head>
<body><p>drivegate: see <a href="/api/v1/status">/api/v1/status</a>.</p></body></html>
)";
}

}  // namespace drivegate::http
