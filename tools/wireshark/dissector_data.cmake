# cmake -DDRIVEGATE=bin/drivegate -DDESCRIPTION=protocols/NAME.toml -DOUT=drivegate_framed_NAME.lua
#   -P dissector_data.cmake
# A described protocol's data for adapters/framed/dissector.lua, as `drivegate protocol dissector`
# prints it from the description file (by path: a copy of the same name in /etc/drivegate/protocols
# must not stand in for the one being built).
execute_process(COMMAND "${DRIVEGATE}" protocol dissector "${DESCRIPTION}"
                OUTPUT_FILE "${OUT}.tmp" ERROR_VARIABLE error RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  file(REMOVE "${OUT}.tmp")
  message(FATAL_ERROR "drivegate protocol dissector ${DESCRIPTION}: ${rc}: ${error}")
endif()
file(COPY_FILE "${OUT}.tmp" "${OUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUT}.tmp")
