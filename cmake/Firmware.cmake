# The pulse firmware (firmware/pulses) for the ATmega328P, built with
# Debian's gcc-avr and avr-libc when they are installed: an ELF (for simavr
# and the tests) and an Intel HEX (for avrdude), installed to
# share/motormix/firmware. Without the cross compiler it is skipped with a
# message; MOTORMIX_BUILD_FIRMWARE=ON (the CI presets) makes that an error.
set(MOTORMIX_BUILD_FIRMWARE AUTO CACHE STRING
  "Build the ATmega328P pulse firmware: ON, OFF, or AUTO (when avr-gcc is found)")
set_property(CACHE MOTORMIX_BUILD_FIRMWARE PROPERTY STRINGS AUTO ON OFF)
set(MOTORMIX_FIRMWARE_ELF "")
if(NOT MOTORMIX_BUILD_FIRMWARE STREQUAL "OFF")
  find_program(MOTORMIX_AVR_GCC avr-gcc)
  find_program(MOTORMIX_AVR_OBJCOPY avr-objcopy)
  find_program(MOTORMIX_AVR_SIZE avr-size)
  # avr-libc is a separate package: the compiler alone cannot build it.
  find_path(MOTORMIX_AVR_LIBC_INCLUDE avr/io.h PATHS /usr/lib/avr/include NO_DEFAULT_PATH)
  if(MOTORMIX_AVR_GCC AND MOTORMIX_AVR_OBJCOPY AND MOTORMIX_AVR_LIBC_INCLUDE)
    set(fw_dir ${CMAKE_CURRENT_BINARY_DIR}/firmware)
    set(MOTORMIX_FIRMWARE_ELF ${fw_dir}/motormix-pulses.elf)
    set(fw_sources
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/main.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/servo_pulses.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot_out.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/sessions.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/pulse_schedule.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/pulse_isr.S
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot.S
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot_reply.c
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot_reply_bits.S
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/serial.c
      ${CMAKE_CURRENT_SOURCE_DIR}/src/link/motormix_link.c)
    set(fw_headers
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/pulse_schedule.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/firmware_state.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/servo_pulses.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot_out.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/sessions.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/pulse_timing.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/dshot_reply.h
      ${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses/serial.h
      ${CMAKE_CURRENT_SOURCE_DIR}/src/link/motormix_link.h)
    # Warnings as errors always: the firmware is built by one known compiler.
    add_custom_command(OUTPUT ${MOTORMIX_FIRMWARE_ELF} ${fw_dir}/motormix-pulses.hex
      COMMAND ${CMAKE_COMMAND} -E make_directory ${fw_dir}
      COMMAND ${MOTORMIX_AVR_GCC} -mmcu=atmega328p -DF_CPU=16000000UL -Os -std=gnu99
        -Wall -Wextra -Werror -ffunction-sections -Wl,--gc-sections
        -I${CMAKE_CURRENT_SOURCE_DIR}/firmware/pulses -I${CMAKE_CURRENT_SOURCE_DIR}/src/link
        ${fw_sources} -o ${MOTORMIX_FIRMWARE_ELF}
      COMMAND ${MOTORMIX_AVR_OBJCOPY} -O ihex -R .eeprom ${MOTORMIX_FIRMWARE_ELF}
        ${fw_dir}/motormix-pulses.hex
      DEPENDS ${fw_sources} ${fw_headers}
      COMMENT "Building the ATmega328P pulse firmware"
      VERBATIM)
    add_custom_target(motormix_firmware ALL DEPENDS ${MOTORMIX_FIRMWARE_ELF})
    install(FILES ${MOTORMIX_FIRMWARE_ELF} ${fw_dir}/motormix-pulses.hex
      DESTINATION ${CMAKE_INSTALL_DATADIR}/motormix/firmware)
    message(STATUS "motormix: building the ATmega328P pulse firmware with ${MOTORMIX_AVR_GCC}")
  elseif(MOTORMIX_BUILD_FIRMWARE STREQUAL "ON")
    message(FATAL_ERROR "MOTORMIX_BUILD_FIRMWARE=ON but gcc-avr / avr-libc are missing "
      "(scripts/install-deps installs them)")
  else()
    message(STATUS "motormix: the ATmega328P pulse firmware is skipped: gcc-avr and avr-libc "
      "are not installed (scripts/install-deps installs them)")
  endif()
endif()
