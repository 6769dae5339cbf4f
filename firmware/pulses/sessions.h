/* The link's sessions and the watchdog's reset count, kept in EEPROM. Each
 * reset starts a session above every one used before, and each link timeout
 * the next: a frame recorded before either is never taken again. */
#ifndef MOTORMIX_SESSIONS_H
#define MOTORMIX_SESSIONS_H

#include <stdint.h>

/* The session frames must name now. */
extern uint32_t g_session;

/* The watchdog resets counted so far, this one included if `watchdog`. */
uint16_t mm_count_resets(uint8_t watchdog);
/* A session above every one used before (at start-up). */
void mm_sessions_start(void);
/* The next session (after a link timeout); the report's last sequence
 * starts again. */
void mm_sessions_next(void);

#endif /* MOTORMIX_SESSIONS_H */
