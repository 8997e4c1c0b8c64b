# SPDX-License-Identifier: Apache-2.0
# traj_verilate_unit(<target> <prefix> <unit> [TRACE] [FAST] PARAMS Name=Value ... [EXTRA file ...])
# Verilates one unit of rtl/ into <target> as class <prefix>, with the
# parameters given (-G), random initial state and X (the lockstep driver,
# host/sim/lockstep.hpp, compares from the first reset edge on). FAST: -O3
# (the tool's builds); TRACE: VCD tracing; EXTRA: more Verilog sources (a
# device primitive's simulation model). Units: the rows of rtl/units.txt.
function(traj_verilate_unit target prefix unit)
  cmake_parse_arguments(V "TRACE;FAST" "" "PARAMS;EXTRA" ${ARGN})
  # The unit's files: its row of rtl/units.txt (the one table of units).
  file(STRINGS ${TRAJ_RTL_DIR}/units.txt rows REGEX "^${unit} ")
  if(NOT rows)
    message(FATAL_ERROR "traj_verilate_unit: ${unit} is not in rtl/units.txt")
  endif()
  string(REGEX REPLACE " +" ";" files "${rows}")
  list(POP_FRONT files)
  list(TRANSFORM files PREPEND ${TRAJ_RTL_DIR}/ OUTPUT_VARIABLE sources)
  list(TRANSFORM V_PARAMS PREPEND -G OUTPUT_VARIABLE gparams)
  set(opt)
  if(V_FAST)
    set(opt -O3)
  endif()
  set(trace)
  if(V_TRACE)
    set(trace TRACE)
  endif()
  verilate(${target} SOURCES ${V_EXTRA} ${sources} TOP_MODULE ${unit} PREFIX ${prefix} INCLUDE_DIRS ${TRAJ_RTL_DIR} ${trace}
    VERILATOR_ARGS -Wall ${opt} --x-assign unique --x-initial unique ${gparams})
  target_link_libraries(${target} PRIVATE trajcore_lockstep)
  target_compile_options(${target} PRIVATE -Wno-unused-parameter)  # Verilator's generated code
endfunction()
