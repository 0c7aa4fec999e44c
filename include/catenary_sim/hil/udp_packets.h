/* catenary_sim hardware in the loop over UDP: the packets, for rig controllers (plain C99).
 *
 * Three packets, each one UDP datagram of fixed size (no fragmentation: all fit an Ethernet MTU):
 *   rig -> simulator  csim_udp_measurement    the contact force measured on each pantograph
 *   simulator -> rig  csim_udp_contact_point  the motion of the wire under each pantograph
 *   simulator -> rig  csim_udp_end            the pass has ended or the simulator stops: stop
 *
 * Byte order: every field is LITTLE-ENDIAN (x86, ARM and most PowerPC rig targets in their usual
 * mode: the structs can be sent and received as they are; a big-endian target swaps each field).
 * Floating point: IEEE 754 binary64. The structs are packed (no padding); the sizes are fixed by
 * CSIM_UDP_MEASUREMENT_SIZE and CSIM_UDP_CONTACT_POINT_SIZE and checked by the simulator.
 *
 * Units: SI (N, m, m/s, m/s^2, s); times in nanoseconds on the sender's own clock (only
 * differences on one clock are used, e.g. CLOCK_MONOTONIC).
 *
 * Sequence numbers: each sender numbers its packets 1, 2, 3, ... (uint32, wrapping to 0 after
 * 2^32 - 1 is allowed); the receiver counts lost, reordered and duplicated packets from them.
 * A measurement answers a contact point by naming its `step` (0: the newest the rig has). A
 * sender that starts numbering again (a restarted rig) is followed again after a hello, or after
 * 8 consecutive numbers from it that are older than the newest taken.
 *
 * Start: the simulator sends contact points to the rig's address given on its command line, or
 * else to the source of the newest valid measurement. A rig that has no contact point yet (so no
 * force to send) sends a hello: a measurement with pantographs = 0, every 50 ms until the first
 * contact point arrives. The pass starts with the first measurement with forces.
 *
 * The rig: the simulator follows one rig, the source (address and port) of the first valid
 * packet it takes (from the address given with --rig, if any, and on the allow-list, if any).
 * Packets from any other source are counted as foreign, logged and ignored, and get no contact
 * points. A hello from the rig's address on another port moves the simulator to that port (a
 * restarted controller with a new socket); an explicit re-arm after the end of a pass (~arm)
 * releases the rig. UDP carries no authentication: this keeps a misconfigured second sender out,
 * not an attacker on the rig network (docs/hil.md, "UDP": isolate the rig network).
 *
 * End: when the pass ends (its end, ~stop, a divergence) or the simulator stops (a signal, its
 * --duration), it sends csim_udp_end (3 copies, for a lost datagram) to the rig. A rig stops on
 * it; a rig should also stop after a time without contact points (the simulator died).
 *
 * Validation by the simulator: magic, version, kind, size, count of pantographs (the scene's
 * number of external pantographs), finite values, forces in [-50, 2000] N (readings in [-50, 0)
 * are taken as 0), head accelerations finite when flagged. A packet failing any check is counted
 * and rejected whole with the reason; the previous measurement stays in effect.
 * docs/hil.md, "UDP", has the same layout as a table. */
#ifndef CATENARY_SIM_HIL_UDP_PACKETS_H
#define CATENARY_SIM_HIL_UDP_PACKETS_H

#include <stdint.h>

#define CSIM_UDP_MAGIC 0x4D495343u /* the bytes 'C' 'S' 'I' 'M' little-endian */
#define CSIM_UDP_VERSION 1u
#define CSIM_UDP_KIND_MEASUREMENT 1u
#define CSIM_UDP_KIND_CONTACT_POINT 2u
#define CSIM_UDP_KIND_END 3u
#define CSIM_UDP_MAX_PANTOGRAPHS 4u /* external pantographs in one packet */
#define CSIM_UDP_MAX_WIRE_POINTS 8u /* collectors x contact wires of one pantograph */

/* csim_udp_measurement.flags */
#define CSIM_UDP_HAS_HEAD_ACCELERATION 0x1u /* head_acceleration[] holds values */

/* csim_udp_contact_point.state_flags: bits 0-7 the mode, then flags */
#define CSIM_UDP_MODE_MASK 0xFFu
#define CSIM_UDP_MODE_WAITING 0u   /* no measurement yet: the line holds its initial static state */
#define CSIM_UDP_MODE_RUNNING 1u   /* stepping with the rig's measurements */
#define CSIM_UDP_MODE_SAFE_HOLD 2u /* no valid measurement for the timeout: train stops, force ramps */
#define CSIM_UDP_MODE_ENDED 3u     /* the pass ended (or diverged, or stopped at a dewirement): the last state, held */
#define CSIM_UDP_MODE_PAUSED 4u    /* held: no steps; velocities 0 */
#define CSIM_UDP_FLAG_HELD 0x100u       /* this period ran without a fresh measurement (held/extrapolated) */
#define CSIM_UDP_FLAG_OVERRUN 0x200u    /* the loop has fallen behind since the last packet (periods dropped) */
#define CSIM_UDP_FLAG_COMPENSATED 0x400u /* heights are predicted over the loop delay (delay compensation) */

/* csim_udp_end.reason */
#define CSIM_UDP_END_FINISHED 1u /* the pass ended (the end of the line, or ~stop once the line settled) */
#define CSIM_UDP_END_DIVERGED 2u /* the simulation diverged: the pass ended */
#define CSIM_UDP_END_SHUTDOWN 3u /* the simulator stops before the pass ended (a signal, --duration) */
#define CSIM_UDP_END_DEWIRED 4u  /* the pass stopped at a dewirement (the scene's pantograph_head.on_dewirement: stop) */

#pragma pack(push, 1)

typedef struct {
  uint32_t magic;        /* CSIM_UDP_MAGIC */
  uint16_t version;      /* CSIM_UDP_VERSION */
  uint16_t kind;         /* CSIM_UDP_KIND_* */
  uint32_t size;         /* bytes of the whole packet: CSIM_UDP_*_SIZE */
  uint32_t sequence;     /* sender's packet number, +1 per packet */
  int64_t send_time_ns;  /* sender's clock when sent */
} csim_udp_header;       /* 24 bytes */

/* rig -> simulator, once per rig period */
typedef struct {
  csim_udp_header header;    /* kind CSIM_UDP_KIND_MEASUREMENT */
  uint64_t answers_step;     /* `step` of the newest contact point the rig had when it measured (0: unknown) */
  int64_t measured_time_ns;  /* when the load cell was sampled, sender's clock (0: unknown: arrival used) */
  uint32_t pantographs;      /* values used below: the scene's external pantographs, in scene order (0: hello) */
  uint32_t flags;            /* CSIM_UDP_HAS_HEAD_ACCELERATION */
  double force[CSIM_UDP_MAX_PANTOGRAPHS];              /* N, total contact force, compression positive */
  double head_acceleration[CSIM_UDP_MAX_PANTOGRAPHS];  /* m/s^2, optional (flag), up positive */
} csim_udp_measurement;

typedef struct {
  double position;       /* m, pantograph reference point along the line */
  double height;         /* m above the rail: the wire under the strip (lowest contact wire per collector, averaged) */
  double velocity;       /* m/s, vertical velocity of that point */
  double acceleration;   /* m/s^2 */
  double path_velocity;  /* m/s, rate of change of `height` seen by the moving pantograph (track it) */
  double applied_force;  /* N, the force applied to the wires in the last step */
  double measurement_age; /* s, age of the measurement in effect (-1: none) */
  uint32_t wire_points;  /* entries used below: collectors x contact wires, collector-major */
  uint8_t on_wire[CSIM_UDP_MAX_WIRE_POINTS];  /* 1: the collector is under that wire */
  double wire_height[CSIM_UDP_MAX_WIRE_POINTS];         /* m (0 where not on the wire) */
  double wire_velocity[CSIM_UDP_MAX_WIRE_POINTS];       /* m/s */
  double wire_path_velocity[CSIM_UDP_MAX_WIRE_POINTS];  /* m/s */
  double wire_force[CSIM_UDP_MAX_WIRE_POINTS];          /* N, >= 0 */
} csim_udp_pantograph_point; /* 324 bytes */

/* simulator -> rig, once per loop period */
typedef struct {
  csim_udp_header header;        /* kind CSIM_UDP_KIND_CONTACT_POINT */
  uint64_t step;                 /* core steps since the start: answer with it (answers_step) */
  uint64_t measurement_step;     /* answers_step of the measurement applied in this period (0: none) */
  uint32_t measurement_sequence; /* header.sequence of that measurement (0: none) */
  uint32_t state_flags;          /* mode (CSIM_UDP_MODE_*) | CSIM_UDP_FLAG_* */
  uint32_t pass_count;           /* +1 when a new pass starts: re-initialise */
  uint32_t pantographs;          /* entries used below */
  uint32_t steps_per_period;     /* core steps per loop period */
  uint32_t reserved;             /* 0 */
  double simulation_time;        /* s */
  double dt;                     /* s, the core's step */
  double speed;                  /* m/s, train speed */
  csim_udp_pantograph_point pantograph[CSIM_UDP_MAX_PANTOGRAPHS];
} csim_udp_contact_point;

/* simulator -> rig, at the end (3 copies with consecutive sequence numbers) */
typedef struct {
  csim_udp_header header;  /* kind CSIM_UDP_KIND_END */
  uint64_t step;           /* core steps at the end */
  uint32_t pass_count;     /* the pass that ended */
  uint32_t reason;         /* CSIM_UDP_END_* */
  double simulation_time;  /* s */
} csim_udp_end;            /* 48 bytes */

#pragma pack(pop)

#define CSIM_UDP_MEASUREMENT_SIZE 112u
#define CSIM_UDP_CONTACT_POINT_SIZE 1384u
#define CSIM_UDP_END_SIZE 48u

#endif /* CATENARY_SIM_HIL_UDP_PACKETS_H */
