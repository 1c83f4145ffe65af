/*
 * What Espressif's Xtensa toolchain (xtensa-esp-elf gcc with its newlib 4) provides that the
 * check's stand-ins (Debian's generic Xtensa gcc, Debian's newlib 3.3 headers) do not.
 *
 * The check includes this file first in every compilation; nothing of the firmware includes it
 * and the real build never sees it. Each entry says what it stands in for. None of them changes
 * what our files are checked against: ESP-IDF's and MicroPython's own headers.
 */
#ifndef OB_TOOLCHAIN_SHIM_H
#define OB_TOOLCHAIN_SHIM_H

/*
 * newlib 3.3 has no setjmp layout for Xtensa (Espressif's newlib has); MicroPython's esp32 port
 * unwinds with setjmp (MICROPY_NLR_SETJMP). The size only matters to code that is linked.
 */
#define _JBLEN 17

/*
 * newlib 3.3 declares _global_impure_ptr `*const`; newlib 4, and ESP-IDF's sys/reent.h after it,
 * without the const. Read newlib 3.3's declaration under another name so ESP-IDF's stands.
 */
#define _global_impure_ptr ob_newlib3_global_impure_ptr
#include </usr/include/newlib/sys/reent.h>
#undef _global_impure_ptr

#endif /* OB_TOOLCHAIN_SHIM_H */
