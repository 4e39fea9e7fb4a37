/*
 * insn_count.c — a QEMU TCG plugin that counts the guest instructions executed between
 * two markers, for `can-bench` (bench/src/qemu.rs builds it with `gcc -shared -fPIC`).
 *
 * Markers. The bench firmware (bench/firmware/count) stores a word to an address of a
 * small "marker window" (plugin argument `base`, 8 bytes per region):
 *
 *     base + 8 * region + 0   start of a measurement of `region`
 *     base + 8 * region + 4   end of a measurement of `region`
 *
 * The window is ordinary guest RAM outside the firmware's linker regions, so the stores
 * have no effect on the guest; the plugin only looks at their addresses.
 *
 * Counting. Every translated instruction gets an execution callback that adds one to a
 * counter; every instruction gets a memory callback for stores, which fires after the
 * store. So a measurement is "instructions executed after the start store, up to and
 * including the end store": the measured code plus the few instructions that form and
 * perform the end store. can-bench measures an empty region (a start marker directly
 * followed by an end marker) and subtracts that overhead.
 *
 * Output. Each completed measurement is appended at once to the file given by the plugin
 * argument `outfile`, as one line `region <n> <instructions>`, and flushed, so that the
 * figures survive however QEMU ends. The firmware is single-core: one counter suffices,
 * vCPU 0 is the only one.
 *
 * Usage:
 *     qemu-system-arm ... -plugin ./insn_count.so,base=0x20110000,outfile=/tmp/x.txt
 *
 * The plugin API declarations below are our own minimal subset, written from the
 * documented QEMU plugin API (docs/devel/tcg-plugins.rst: "qemu_plugin_install",
 * "qemu_plugin_version", translation-time registration of per-instruction execution and
 * memory callbacks, "qemu_plugin_outs"), because Debian 12 ships no `qemu-plugin.h`
 * (see docs/benchmarks.md). Only opaque handles, scalar typedefs, the enum values used
 * and the function prototypes called are declared. QEMU refuses a plugin whose declared
 * API version lies outside its own [minimum, current] range; we declare 1, the current
 * version of Debian 12's QEMU 7.2 (`-DTWOCAN_QEMU_PLUGIN_VERSION=n` overrides it for
 * another QEMU whose range excludes 1, as long as the calls below keep their form).
 */
#include <inttypes.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* ---- minimal plugin API declarations (our own; see the header comment) ---------- */

#define TWOCAN_EXPORT __attribute__((visibility("default")))

#ifndef TWOCAN_QEMU_PLUGIN_VERSION
#define TWOCAN_QEMU_PLUGIN_VERSION 1
#endif

typedef uint64_t qemu_plugin_id_t;
typedef uint32_t qemu_plugin_meminfo_t;

/* Opaque to plugins. */
typedef struct qemu_info_t qemu_info_t;
struct qemu_plugin_tb;
struct qemu_plugin_insn;

enum qemu_plugin_cb_flags {
    QEMU_PLUGIN_CB_NO_REGS = 0,
};

enum qemu_plugin_mem_rw {
    QEMU_PLUGIN_MEM_R = 1,
    QEMU_PLUGIN_MEM_W = 2,
};

typedef void (*qemu_plugin_vcpu_tb_trans_cb_t)(qemu_plugin_id_t id, struct qemu_plugin_tb *tb);
typedef void (*qemu_plugin_vcpu_udata_cb_t)(unsigned int vcpu_index, void *userdata);
typedef void (*qemu_plugin_vcpu_mem_cb_t)(unsigned int vcpu_index, qemu_plugin_meminfo_t info,
                                          uint64_t vaddr, void *userdata);
typedef void (*qemu_plugin_udata_cb_t)(qemu_plugin_id_t id, void *userdata);

void qemu_plugin_register_vcpu_tb_trans_cb(qemu_plugin_id_t id, qemu_plugin_vcpu_tb_trans_cb_t cb);
size_t qemu_plugin_tb_n_insns(const struct qemu_plugin_tb *tb);
struct qemu_plugin_insn *qemu_plugin_tb_get_insn(const struct qemu_plugin_tb *tb, size_t idx);
void qemu_plugin_register_vcpu_insn_exec_cb(struct qemu_plugin_insn *insn,
                                            qemu_plugin_vcpu_udata_cb_t cb,
                                            enum qemu_plugin_cb_flags flags, void *userdata);
void qemu_plugin_register_vcpu_mem_cb(struct qemu_plugin_insn *insn, qemu_plugin_vcpu_mem_cb_t cb,
                                      enum qemu_plugin_cb_flags flags, enum qemu_plugin_mem_rw rw,
                                      void *userdata);
void qemu_plugin_register_atexit_cb(qemu_plugin_id_t id, qemu_plugin_udata_cb_t cb, void *userdata);
void qemu_plugin_outs(const char *string);

/* ---- the plugin ------------------------------------------------------------------ */

TWOCAN_EXPORT int qemu_plugin_version = TWOCAN_QEMU_PLUGIN_VERSION;

/* Regions the window can address. */
#define MAX_REGIONS 64u

static uint64_t executed;               /* instructions executed so far (vCPU 0) */
static uint64_t window_base;            /* marker window start */
static uint64_t started_at[MAX_REGIONS];
static bool open_region[MAX_REGIONS];
static uint64_t completed;              /* measurements written */
static uint64_t unmatched;              /* end markers without a start */
static FILE *out;

static void on_insn(unsigned int vcpu_index, void *userdata)
{
    (void)vcpu_index;
    (void)userdata;
    executed++;
}

static void on_store(unsigned int vcpu_index, qemu_plugin_meminfo_t info, uint64_t vaddr,
                     void *userdata)
{
    (void)vcpu_index;
    (void)info;
    (void)userdata;
    if (vaddr < window_base || vaddr >= window_base + 8u * MAX_REGIONS) {
        return;
    }
    uint64_t offset = vaddr - window_base;
    unsigned region = (unsigned)(offset / 8u);
    if ((offset & 7u) == 0) {
        started_at[region] = executed;
        open_region[region] = true;
    } else if ((offset & 7u) == 4) {
        if (!open_region[region]) {
            unmatched++;
            return;
        }
        open_region[region] = false;
        fprintf(out, "region %u %" PRIu64 "\n", region, executed - started_at[region]);
        fflush(out);
        completed++;
    }
}

static void on_translate(qemu_plugin_id_t id, struct qemu_plugin_tb *tb)
{
    (void)id;
    size_t n = qemu_plugin_tb_n_insns(tb);
    for (size_t i = 0; i < n; i++) {
        struct qemu_plugin_insn *insn = qemu_plugin_tb_get_insn(tb, i);
        qemu_plugin_register_vcpu_insn_exec_cb(insn, on_insn, QEMU_PLUGIN_CB_NO_REGS, NULL);
        qemu_plugin_register_vcpu_mem_cb(insn, on_store, QEMU_PLUGIN_CB_NO_REGS,
                                         QEMU_PLUGIN_MEM_W, NULL);
    }
}

static void at_exit(qemu_plugin_id_t id, void *userdata)
{
    (void)id;
    (void)userdata;
    fprintf(out, "total %" PRIu64 " completed %" PRIu64 " unmatched %" PRIu64 "\n", executed,
            completed, unmatched);
    fflush(out);
    fclose(out);
    out = NULL;
}

/* Accepts `key=value` (QEMU >= 6.1) and the older `arg=key=value` spelling. */
static const char *value_of(const char *arg, const char *key)
{
    if (strncmp(arg, "arg=", 4) == 0) {
        arg += 4;
    }
    size_t k = strlen(key);
    if (strncmp(arg, key, k) == 0 && arg[k] == '=') {
        return arg + k + 1;
    }
    return NULL;
}

TWOCAN_EXPORT int qemu_plugin_install(qemu_plugin_id_t id, const qemu_info_t *info, int argc,
                                      char **argv)
{
    (void)info;
    const char *path = NULL;
    bool have_base = false;
    for (int i = 0; i < argc; i++) {
        const char *v;
        if ((v = value_of(argv[i], "base")) != NULL) {
            char *end = NULL;
            window_base = strtoull(v, &end, 0);
            have_base = end != v && *end == '\0';
        } else if ((v = value_of(argv[i], "outfile")) != NULL) {
            path = v;
        } else {
            qemu_plugin_outs("insn_count: unknown argument\n");
            return -1;
        }
    }
    if (!have_base || path == NULL) {
        qemu_plugin_outs("insn_count: needs base=ADDRESS and outfile=PATH\n");
        return -1;
    }
    out = fopen(path, "w");
    if (out == NULL) {
        qemu_plugin_outs("insn_count: cannot open the output file\n");
        return -1;
    }
    fprintf(out, "window 0x%" PRIx64 "\n", window_base);
    fflush(out);
    qemu_plugin_register_vcpu_tb_trans_cb(id, on_translate);
    qemu_plugin_register_atexit_cb(id, at_exit, NULL);
    return 0;
}
