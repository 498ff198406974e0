# cmake -DPROTOCOLS="a.toml|b.toml" -DOUT=... -P embed_protocols.cmake: the shipped descriptions as
# C++ raw string literals (settings.cpp includes them), so that the plugin finds them wherever it
# runs (the build tree, a test, a fuzzer), after the copies in /etc/drivegate/protocols and
# /usr/share/drivegate/protocols.
string(REPLACE "|" ";" PROTOCOLS "${PROTOCOLS}")
set(body "")
foreach(file IN LISTS PROTOCOLS)
  get_filename_component(name "${file}" NAME_WE)
  file(READ "${file}" text)
  string(FIND "${text}" ")protocol\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${file} holds )protocol\" and cannot be a raw string with that delimiter")
  endif()
  string(APPEND body "    {\"${name}\", R\"protocol(${text})protocol\"},\n")
endforeach()
list(LENGTH PROTOCOLS count)
file(WRITE "${OUT}.tmp"
     "// Generated from adapters/framed/protocols/ by embed_protocols.cmake: edit those files.\n"
     "inline constexpr std::array<ShippedDescription, ${count}> kShippedProtocols = {{\n${body}}};\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
