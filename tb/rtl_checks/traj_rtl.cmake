# SPDX-License-Identifier: Apache-2.0
# The RTL checks of one unit under CTest, one function for every unit:
#
#   traj_rtl_unit(NAME <top>
#     [FILES <file> ...]          files relative to rtl/ (default: the unit's row in rtl/units.txt)
#     [PARAMS <P=V> ...]          parameters of the default configuration
#     [CONFIGS <name:P=V,P=V> ...] further configurations for lint, Icarus and Yosys
#     [BAD_PARAMS <P=V[,P=V]> ...] each must be rejected at elaboration by all three tools
#     [FORMAL <P=V,P=V> ...]      configurations proved by scripts/formal.sh (BMC + induction)
#     [SYNTH])                    Yosys synth_ice40 smoke of the unit
#
# Tests, named rtl.<kind>.<unit>[.<name>]:
#   rtl.lint.<unit>[.<config>]          verilator --lint-only -Wall -Wpedantic
#   rtl.iverilog.<unit>[.<config>]      iverilog -g2012 -Wall, silent, and vvp runs (no $fatal)
#   rtl.yosys.<unit>[.<config>]         yosys hierarchy -check; proc; check -assert
#   rtl.synth_ice40.<unit>              yosys synth_ice40; check -assert
#   rtl.param_rejected.<tool>.<unit>.<P_V>   tool in verilator, iverilog, yosys
#   rtl.formal.<unit>.<V_V_...>         yosys-smtbmc with z3
# Place-and-route figures come from scripts/synth.sh (a benchmark, not a test).
find_program(VERILATOR_BIN verilator REQUIRED)
find_program(IVERILOG_BIN iverilog REQUIRED)
find_program(VVP_BIN vvp REQUIRED)
find_program(YOSYS_BIN yosys REQUIRED)
find_program(SMTBMC_BIN yosys-smtbmc REQUIRED)

set(TRAJ_RTL_UNITS_FILE ${TRAJ_RTL_DIR}/units.txt)
# Yosys' simulation model of the iCE40 SB_MAC16, cut from its cell library at
# configure time, for the co-simulations of traj_add's DSP form (UseDsp = 1)
find_file(TRAJ_ICE40_CELLS_SIM cells_sim.v PATHS /usr/share/yosys/ice40 /usr/local/share/yosys/ice40
  NO_DEFAULT_PATH REQUIRED)
file(READ ${TRAJ_ICE40_CELLS_SIM} cells_sim)
string(FIND "${cells_sim}" "module SB_MAC16" mac_at)
if(mac_at LESS 0)
  message(FATAL_ERROR "no SB_MAC16 in ${TRAJ_ICE40_CELLS_SIM}")
endif()
string(SUBSTRING "${cells_sim}" ${mac_at} -1 mac_model)
string(FIND "${mac_model}" "endmodule" mac_end)
math(EXPR mac_end "${mac_end} + 9")
string(SUBSTRING "${mac_model}" 0 ${mac_end} mac_model)
set(TRAJ_SB_MAC16_SIM ${CMAKE_CURRENT_BINARY_DIR}/sb_mac16_sim.v)
file(WRITE ${TRAJ_SB_MAC16_SIM} "// SB_MAC16 from ${TRAJ_ICE40_CELLS_SIM} (Yosys, ISC licence)\n"
  "/* verilator lint_off WIDTH */\n/* verilator lint_off DECLFILENAME */\n/* verilator lint_off UNUSEDSIGNAL */\n"
  "/* verilator lint_off UNUSEDPARAM */\n${mac_model}\n")
unset(cells_sim)
unset(mac_model)
set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS ${TRAJ_RTL_UNITS_FILE})

# files of <unit> from rtl/units.txt, relative to rtl/
function(traj_rtl_unit_files unit out_var)
  file(STRINGS ${TRAJ_RTL_UNITS_FILE} rows REGEX "^${unit}[ \t]")
  if(NOT rows)
    message(FATAL_ERROR "traj_rtl_unit: no unit ${unit} in ${TRAJ_RTL_UNITS_FILE}")
  endif()
  list(GET rows 0 row)
  separate_arguments(row UNIX_COMMAND "${row}")
  list(REMOVE_AT row 0)
  set(${out_var} ${row} PARENT_SCOPE)
endfunction()

# "P=V,P=V" -> the per-tool parameter arguments and a test-name suffix
function(traj_rtl_param_args top params verilator_var iverilog_var yosys_var name_var)
  string(REPLACE "," ";" plist "${params}")
  set(v "")
  set(i "")
  set(y "")
  set(n "")
  foreach(p IN LISTS plist)
    string(REPLACE "=" ";" pv "${p}")
    list(GET pv 0 pname)
    list(GET pv 1 pval)
    list(APPEND v -G${p})
    string(APPEND i " -P${top}.${p}")
    string(APPEND y " -set ${pname} ${pval}")
    list(APPEND n ${pname}_${pval})
  endforeach()
  if(y)
    set(y "chparam${y} ${top}; ")
  endif()
  list(JOIN n "_" n)
  set(${verilator_var} ${v} PARENT_SCOPE)
  set(${iverilog_var} "${i}" PARENT_SCOPE)
  set(${yosys_var} "${y}" PARENT_SCOPE)
  set(${name_var} "${n}" PARENT_SCOPE)
endfunction()

# lint, Icarus and Yosys checks of one configuration of <top>
function(traj_rtl_add_elaboration top suffix params files)
  traj_rtl_param_args(${top} "${params}" vargs iargs yargs pname)
  list(JOIN files " " files_str)
  set(vvp ${CMAKE_CURRENT_BINARY_DIR}/${top}${suffix}.vvp)
  add_test(NAME rtl.lint.${top}${suffix}
    COMMAND ${VERILATOR_BIN} --lint-only -Wall -Wpedantic -I${TRAJ_RTL_DIR} --top-module ${top}
            ${vargs} ${files})
  # Icarus must elaborate silently (no "sorry" or other warning) and the
  # parameter checks ($fatal at time 0 under Icarus) must not fire.
  add_test(NAME rtl.iverilog.${top}${suffix}
    COMMAND bash -c "out=$(${IVERILOG_BIN} -g2012 -Wall -I${TRAJ_RTL_DIR} -s ${top}${iargs} -o ${vvp} ${files_str} 2>&1) || { echo \"$out\"; exit 1; }; if [ -n \"$out\" ]; then echo \"$out\"; exit 1; fi; ${VVP_BIN} -n ${vvp}")
  add_test(NAME rtl.yosys.${top}${suffix}
    COMMAND ${YOSYS_BIN} -q -p "read_verilog -sv -I${TRAJ_RTL_DIR} ${files_str}; ${yargs}hierarchy -check -top ${top}; proc; check -assert")
endfunction()

# one bad parameter set must stop elaboration in Verilator, Icarus and Yosys
# (each test passes when its tool fails)
function(traj_rtl_add_param_rejected top params files)
  traj_rtl_param_args(${top} "${params}" vargs iargs yargs pname)
  list(JOIN files " " files_str)
  set(vvp ${CMAKE_CURRENT_BINARY_DIR}/${top}_bad_${pname}.vvp)
  set(base rtl.param_rejected)
  add_test(NAME ${base}.verilator.${top}.${pname}
    COMMAND ${VERILATOR_BIN} --lint-only -Wall -I${TRAJ_RTL_DIR} --top-module ${top} ${vargs} ${files})
  add_test(NAME ${base}.iverilog.${top}.${pname}
    COMMAND bash -c "${IVERILOG_BIN} -g2012 -I${TRAJ_RTL_DIR} -s ${top}${iargs} -o ${vvp} ${files_str} || exit 1; ${VVP_BIN} -n ${vvp} | grep -q FATAL && exit 1; exit 0")
  add_test(NAME ${base}.yosys.${top}.${pname}
    COMMAND ${YOSYS_BIN} -q -p "read_verilog -sv -I${TRAJ_RTL_DIR} ${files_str}; ${yargs}hierarchy -check -top ${top}")
  set_tests_properties(${base}.verilator.${top}.${pname} ${base}.iverilog.${top}.${pname}
    ${base}.yosys.${top}.${pname} PROPERTIES WILL_FAIL TRUE)
endfunction()

function(traj_rtl_unit)
  cmake_parse_arguments(PARSE_ARGV 0 U "SYNTH" "NAME" "FILES;PARAMS;CONFIGS;BAD_PARAMS;FORMAL")
  set(top ${U_NAME})
  if(NOT U_FILES)
    traj_rtl_unit_files(${top} U_FILES)
  endif()
  list(TRANSFORM U_FILES PREPEND ${TRAJ_RTL_DIR}/ OUTPUT_VARIABLE files)
  list(JOIN U_PARAMS "," params)

  traj_rtl_add_elaboration(${top} "" "${params}" "${files}")
  foreach(cfg IN LISTS U_CONFIGS)
    string(FIND "${cfg}" ":" colon)
    string(SUBSTRING "${cfg}" 0 ${colon} cname)
    math(EXPR from "${colon} + 1")
    string(SUBSTRING "${cfg}" ${from} -1 cparams)
    traj_rtl_add_elaboration(${top} ".${cname}" "${cparams}" "${files}")
  endforeach()

  foreach(bad IN LISTS U_BAD_PARAMS)
    traj_rtl_add_param_rejected(${top} "${bad}" "${files}")
  endforeach()

  if(U_SYNTH)
    list(JOIN files " " files_str)
    traj_rtl_param_args(${top} "${params}" vargs iargs yargs pname)
    add_test(NAME rtl.synth_ice40.${top}
      COMMAND ${YOSYS_BIN} -q -p "read_verilog -sv -I${TRAJ_RTL_DIR} ${files_str}; ${yargs}synth_ice40 -top ${top}; check -assert")
    set_tests_properties(rtl.synth_ice40.${top} PROPERTIES TIMEOUT 900)
  endif()

  foreach(cfg IN LISTS U_FORMAL)
    string(REGEX REPLACE "[A-Za-z]+=" "" cname "${cfg}")
    string(REPLACE "," "_" cname "${cname}")
    string(REPLACE "," ";" cparams "${cfg}")
    add_test(NAME rtl.formal.${top}.${cname}
      COMMAND ${TRAJ_SCRIPTS_DIR}/formal.sh ${top} ${CMAKE_CURRENT_BINARY_DIR}/formal_${top}_${cname} ${cparams})
    set_tests_properties(rtl.formal.${top}.${cname} PROPERTIES TIMEOUT 1800)
  endforeach()
endfunction()
