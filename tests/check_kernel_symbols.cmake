# Fails unless the AVX kernel's object exports its kKernel and no code: no global or weak function
# symbol (nm types T, W, i), which the linker could share with code built for the baseline CPU.
# Weak data (the typeinfo objects UBSan's function checks emit, type V) carries no instructions.
# Run by ctest (avx_kernel_shares_no_code) with -DNM= and -DOBJECTS= (a list).
list(FILTER OBJECTS INCLUDE REGEX "newton_lagrange_kernel_avx")
list(LENGTH OBJECTS count)
if(NOT count EQUAL 1)
  message(FATAL_ERROR "expected one AVX kernel object, found ${count}: ${OBJECTS}")
endif()
execute_process(COMMAND ${NM} -C --defined-only ${OBJECTS} OUTPUT_VARIABLE symbols
                RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${NM} failed on ${OBJECTS}")
endif()
if(NOT symbols MATCHES "[0-9a-f]+ [DR] accelcal::internal::newton_kernel::avx::kKernel\n")
  message(FATAL_ERROR "the AVX kernel object does not define its kKernel:\n${symbols}")
endif()
string(REGEX MATCHALL "[^\n]* [TWi] [^\n]*" code "${symbols}")
if(code)
  message(FATAL_ERROR "the AVX kernel object exports code the linker could share:\n${code}")
endif()
message(STATUS "AVX kernel object: kKernel and no shared code")
