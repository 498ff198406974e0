# cmake -DPAGE_DIR=... -DOUT=... -P embed.cmake: the status page as the daemon serves it, one
# self-contained document. page.html links page.css and page.js so that a web developer can open
# and edit the three files as they are; the Content-Security-Policy the server sends allows no
# other file, so here the stylesheet and the script are put inline where page.html links them,
# and the result is written as a C++ raw string literal (included by ../page.cpp).
file(READ "${PAGE_DIR}/page.html" html)
file(READ "${PAGE_DIR}/page.css" css)
file(READ "${PAGE_DIR}/page.js" js)
set(link "<link rel=\"stylesheet\" href=\"page.css\">\n")
set(script "<script src=\"page.js\"></script>\n")
foreach(what link script)
  string(FIND "${html}" "${${what}}" at)
  if(at EQUAL -1)
    message(FATAL_ERROR "${PAGE_DIR}/page.html: no ${${what}}")
  endif()
endforeach()
string(REPLACE "${link}" "<style>\n${css}</style>\n" html "${html}")
string(REPLACE "${script}" "<script>\n${js}</script>\n" html "${html}")
string(FIND "${html}" ")page\"" clash)
if(NOT clash EQUAL -1)
  message(FATAL_ERROR "the status page holds )page\" and cannot be a raw string with that delimiter")
endif()
file(WRITE "${OUT}.tmp" "// Generated from daemon/http/page/ by embed.cmake: edit those files, not this one.\n"
     "constexpr std::string_view kPage = R\"page(${html})page\";\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
