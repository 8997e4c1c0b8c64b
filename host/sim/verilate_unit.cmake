# SPDX-License-Identifier: Apache-2.0
# traj_verilate_unit(<target> <prefix> <unit> [TRACE] [FAST] PARAMS Name=Value ...)
# Verilates one unit of rtl/ into <target> as class <prefix>, with the
# parameters given (-G), random initial state and X (the lockstep driver,
# host/sim/lockstep.hpp, compares from the first reset edge on). FAST: -O3
# (the tool's builds); TRACE: VCD tracing. Units: traj_fd_engine, traj_bcu,
# traj_bcu_gen, traj_core.
function(traj_verilate_unit target prefix unit)
  cmake_parse_arguments(V "TRACE;FAST" "" "PARAMS" ${ARGN})
  set(sources_traj_fd_engine traj_fd_engine.sv)
  set(sources_traj_bcu traj_bcu.sv)
  set(sources_traj_bcu_gen traj_bcu.sv traj_bcu_gen.sv)
  set(sources_traj_core traj_fd_engine.sv traj_bcu.sv traj_bcu_gen.sv traj_core.sv)
  if(NOT DEFINED sources_${unit})
    message(FATAL_ERROR "traj_verilate_unit: unknown unit ${unit}")
  endif()
  list(TRANSFORM sources_${unit} PREPEND ${TRAJ_RTL_DIR}/ OUTPUT_VARIABLE sources)
  list(TRANSFORM V_PARAMS PREPEND -G OUTPUT_VARIABLE gparams)
  set(opt)
  if(V_FAST)
    set(opt -O3)
  endif()
  set(trace)
  if(V_TRACE)
    set(trace TRACE)
  endif()
  verilate(${target} SOURCES ${sources} TOP_MODULE ${unit} PREFIX ${prefix} INCLUDE_DIRS ${TRAJ_RTL_DIR} ${trace}
    VERILATOR_ARGS -Wall ${opt} --x-assign unique --x-initial unique ${gparams})
  target_link_libraries(${target} PRIVATE trajcore_lockstep)
  target_compile_options(${target} PRIVATE -Wno-unused-parameter)  # Verilator's generated code
endfunction()
