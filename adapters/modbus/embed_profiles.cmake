# cmake -DPROFILES="a.toml|b.toml" -DOUT=... -P embed_profiles.cmake: the shipped profiles as C++
# raw string literals, so that the plugin finds them wherever it runs (the build tree, a test, a
# fuzzer), after the copies in /etc/drivegate/profiles and /usr/share/drivegate/profiles.
# Each text is a char array and its view takes the array's size: a view made from a pointer alone
# counts the characters at compile time, one constexpr step each, and the library outgrew clang's
# step limit (68 profiles, 0.6 MB: "constexpr evaluation hit maximum step limit").
string(REPLACE "|" ";" PROFILES "${PROFILES}")
set(texts "")
set(body "")
set(index 0)
foreach(file IN LISTS PROFILES)
  get_filename_component(name "${file}" NAME_WE)
  file(READ "${file}" text)
  string(FIND "${text}" ")profile\"" clash)
  if(NOT clash EQUAL -1)
    message(FATAL_ERROR "${file} holds )profile\" and cannot be a raw string with that delimiter")
  endif()
  string(APPEND texts "inline constexpr char kProfileText${index}[] = R\"profile(${text})profile\";\n")
  string(APPEND body
         "    {\"${name}\", {kProfileText${index}, sizeof kProfileText${index} - 1}},\n")
  math(EXPR index "${index} + 1")
endforeach()
list(LENGTH PROFILES count)
file(WRITE "${OUT}.tmp"
     "// Generated from adapters/modbus/profiles/ by embed_profiles.cmake: edit those files.\n"
     "${texts}"
     "inline constexpr std::array<ShippedProfile, ${count}> kShippedProfiles = {{\n${body}}};\n")
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
