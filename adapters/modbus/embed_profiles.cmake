# cmake -DPROFILES="a.toml|b.toml" -DOUT=... -P embed_profiles.cmake: the shipped profiles as C++
# raw string literals, so that the plugin finds them wherever it runs (the build tree, a test, a
# fuzzer), after the copies in /etc/drivegate/profiles and /usr/share/drivegate/profiles.
string(REPLACE "|" ";" PROFILES "${PROFILES}")
set(body "")
foreach(file IN LISTS PROFILES)
  get_filename_component(name "${file}" NAME_WE)
  file(READ "${file}" text)
  string(FIND "${text}" ")profile\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${file} holds )profile\" and cannot be a raw string with that delimiter")
  endif()
  string(APPEND body "    {\"${name}\", R\"profile(${text})profile\"},\n")
endforeach()
list(LENGTH PROFILES count)
file(WRITE "${OUT}.tmp"
     "// Generated from adapters/modbus/profiles/ by embed_profiles.cmake: edit those files.\n"
     "inline constexpr std::array<ShippedProfile, ${count}> kShippedProfiles = {{\n${body}}};\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
