// Which document a request gets: pure (a method and a target in, a response out), so every
// route, refusal and header is tested without a socket.
#pragma once

#include <string>
#include <string_view>

#include "content.h"

namespace drivegate::http {

struct Response {
  unsigned status = 200;
  std::string content_type;
  std::string body;
  std::string allow;  // for 405: the methods that are
};

// GET and HEAD only (the server strips HEAD's body). Query strings are ignored except where a
// route reads them. Unknown targets are 404; other methods 405.
Response route(std::string_view method, std::string_view target, Content& content);

// The status page (page.cpp): HTML, CSS and JavaScript in one document, no external asset.
std::string_view status_page();

}  // namespace drivegate::http
