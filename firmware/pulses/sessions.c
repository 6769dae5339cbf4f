#include "sessions.h"

#include <avr/eeprom.h>

#include "firmware_state.h"

#define WATCHDOG_COUNT_ADDRESS ((uint16_t*)0)
/* The highest session base used (a multiple of 2^16): each reset starts
 * above it, so no session number ever comes back. */
#define SESSION_BASE_ADDRESS ((uint32_t*)4)
#define SESSION_BASE_STEP 0x10000UL

uint32_t g_session;

uint16_t mm_count_resets(uint8_t watchdog) {
  uint16_t resets = eeprom_read_word(WATCHDOG_COUNT_ADDRESS);
  if (resets == 0xFFFFu) resets = 0; /* a fresh EEPROM */
  if (watchdog) eeprom_update_word(WATCHDOG_COUNT_ADDRESS, ++resets);
  return resets;
}

/* The next base, written down before it is used. */
void mm_sessions_start(void) {
  uint32_t base = eeprom_read_dword(SESSION_BASE_ADDRESS);
  if (base == 0xFFFFFFFFUL) base = 0; /* a fresh EEPROM */
  base += SESSION_BASE_STEP;
  eeprom_update_dword(SESSION_BASE_ADDRESS, base);
  g_session = base + 1u;
}

/* Past a base's 2^16 numbers the next base is written down first. */
void mm_sessions_next(void) {
  ++g_session;
  if ((g_session & (SESSION_BASE_STEP - 1u)) == 0u) {
    eeprom_update_dword(SESSION_BASE_ADDRESS, g_session);
    ++g_session;
  }
  g_report.last_sequence = 0;
}
