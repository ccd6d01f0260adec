"""The MultiWii Serial Protocol (MSP), sans-IO: frames, a resyncing stream parser, and the
mission-relevant commands' payloads (seed 004; INAV 9.1's `src/main/msp/`, `fc/fc_msp.c`)."""
