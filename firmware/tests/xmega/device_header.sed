# Makes avr/iox128a3_host.h from avr-libc's avr/iox128a3.h for the host model (see include/avr/io.h):
# the register types become the model's, each peripheral's address an address in the host's register file, and
# the 16/32-bit register unions are left to include/avr/io.h (C++ forbids members with assignment operators in
# anonymous structs). Nothing else changes: structs, offsets, bit masks and vectors stay avr-libc's.
s/^typedef volatile uint8_t register8_t;/typedef xm_reg8 register8_t;/
s/^typedef volatile uint16_t register16_t;/typedef xm_reg16 register16_t;/
s/^typedef volatile uint32_t register32_t;/typedef xm_reg32 register32_t;/
s/(\*(\([A-Za-z0-9_]*\) \*) \(0x[0-9A-Fa-f]*\))/(*(\1 *) XM_IO(\2))/
s/^#undef _WORDREGISTER$//
s/^#undef _DWORDREGISTER$//
s/^#define _WORDREGISTER(regname)/#define _WORDREGISTER_UNION(regname)/
s/^#define _DWORDREGISTER(regname)/#define _DWORDREGISTER_UNION(regname)/
