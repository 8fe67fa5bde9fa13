/**
 * \file engine.c
 * The emulator's native firmware engine: build/wasm/pocketbot.wasm turned into C by wasm2c and compiled by gcc, with
 * the JNI entry points of emulator/.../firmware/NativeEngine.kt (the JVM side; change both together) and the small
 * wasm2c runtime it needs. Built by `make -C firmware native-engine` into
 * build/native/lib/<os>-<arch>/libpocketbot-firmware.so, which the emulator's jar carries.
 *
 * One wasm2c instance per robot, each with its own linear memory (calloc'd, bounds-checked on every access) and its
 * own globals and table, so robots share nothing but the code. The firmware imports nothing (sim_abi.h): a call in
 * never calls back into the JVM. A trap (out-of-bounds access, bad indirect call, runaway recursion) unwinds to the
 * JNI entry point that made the call and becomes a Java exception; the instance stays memory-safe and isolated.
 *
 * How wasm2c's code is built for it (the firmware Makefile): bounds checks in code against the memory's constant size
 * ENGINE_MEMORY_BYTES (no guard pages, whose SIGSEGV handler would take the JVM's), which rests on what the emulator
 * checks before it runs firmware natively (FirmwareImage: no memory.grow), and a call depth count per thread
 * (call_depth.h) in place of the guard page that would catch runaway recursion.
 *
 * Threads: robots are stepped on several threads, each robot on one at a time; the trap target is per thread, the
 * function type registry is filled once, when the library loads.
 */
#include <jni.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "pocketbot.h"

#ifndef POCKETBOT_WASM_SHA256
#error "POCKETBOT_WASM_SHA256 (the SHA-256 of the wasm this library was built from) must be defined"
#endif

#define EXPORT(name) JNIEXPORT JNICALL Java_org_pocketbot_emulator_firmware_NativeEngine_##name

/* ---- the wasm2c runtime (wasm-rt.h), for this library alone --------------------------------------------------- */

#ifndef ENGINE_MEMORY_BYTES
#error "ENGINE_MEMORY_BYTES (the firmware's linear memory size, which never changes) must be defined"
#endif

/* initial-exec: a plain %fs-relative access, no call (the library's static TLS is these 12 bytes). */
static __thread jmp_buf *trap_target __attribute__((tls_model("initial-exec")));
__thread uint32_t engine_call_depth __attribute__((tls_model("initial-exec")));

/* Not wasm traps: the C heap could not hold a new instance; the module's memory is not the one the bounds checks
 * were compiled for. */
#define TRAP_NO_MEMORY 1000
#define TRAP_MEMORY_SIZE 1001

void wasm_rt_init(void)
{
}

bool wasm_rt_is_initialized(void)
{
    return true;
}

WASM_RT_NO_RETURN void wasm_rt_trap(wasm_rt_trap_t code)
{
    /* Every call into an instance goes through GUARDED, which sets the target first. */
    longjmp(*trap_target, (int)code);
}

typedef struct {
    uint32_t params, results;
    wasm_rt_type_t types[16];
} func_type_t;

static func_type_t func_types_registered[64];
static uint32_t func_type_count;

/* Equal signatures get equal ids, which call_indirect compares. */
uint32_t wasm_rt_register_func_type(uint32_t params, uint32_t results, ...)
{
    func_type_t t = {params, results, {0}};
    if (params + results > 16)
        abort(); /* at load time, never while robots run: this firmware's widest signature has 8 */
    va_list args;
    va_start(args, results);
    for (uint32_t i = 0; i < params + results; i++)
        t.types[i] = va_arg(args, wasm_rt_type_t);
    va_end(args);
    for (uint32_t i = 0; i < func_type_count; i++)
        if (memcmp(&func_types_registered[i], &t, sizeof t) == 0)
            return i + 1;
    if (func_type_count == sizeof func_types_registered / sizeof func_types_registered[0])
        abort();
    func_types_registered[func_type_count++] = t;
    return func_type_count;
}

void wasm_rt_allocate_memory(wasm_rt_memory_t *memory, uint32_t initial_pages, uint32_t max_pages)
{
    uint64_t bytes = (uint64_t)initial_pages * 65536u;
    if (bytes != ENGINE_MEMORY_BYTES)
        longjmp(*trap_target, TRAP_MEMORY_SIZE);
    memory->data = calloc(bytes, 1);
    if (memory->data == NULL)
        longjmp(*trap_target, TRAP_NO_MEMORY);
    memory->size = (uint32_t)bytes;
    memory->pages = initial_pages;
    memory->max_pages = max_pages;
}

/* Never called: the emulator only runs firmware natively that has no memory.grow (FirmwareImage). The bounds checks
 * compare with ENGINE_MEMORY_BYTES, and the JVM reads the memory through a buffer over `data`, which a grow would move. */
uint32_t wasm_rt_grow_memory(wasm_rt_memory_t *memory, uint32_t pages)
{
    (void)memory;
    (void)pages;
    return UINT32_MAX;
}

void wasm_rt_free_memory(wasm_rt_memory_t *memory)
{
    free(memory->data);
}

void wasm_rt_allocate_funcref_table(wasm_rt_funcref_table_t *table, uint32_t elements, uint32_t max_elements)
{
    table->data = calloc(elements ? elements : 1, sizeof(wasm_rt_funcref_t));
    if (table->data == NULL)
        longjmp(*trap_target, TRAP_NO_MEMORY);
    table->size = elements;
    table->max_size = max_elements;
}

void wasm_rt_free_funcref_table(wasm_rt_funcref_table_t *table)
{
    free(table->data);
}

/* ---- calls in from the JVM --------------------------------------------------------------------------------------- */

static const char *trap_message(int code)
{
    switch (code) {
    case WASM_RT_TRAP_OOB: return "firmware trapped: out-of-bounds access to linear memory or a table";
    case WASM_RT_TRAP_INT_OVERFLOW: return "firmware trapped: integer overflow on division or conversion";
    case WASM_RT_TRAP_DIV_BY_ZERO: return "firmware trapped: integer division by zero";
    case WASM_RT_TRAP_INVALID_CONVERSION: return "firmware trapped: conversion of NaN to an integer";
    case WASM_RT_TRAP_UNREACHABLE: return "firmware trapped: unreachable executed";
    case WASM_RT_TRAP_CALL_INDIRECT: return "firmware trapped: invalid indirect call";
    case WASM_RT_TRAP_EXHAUSTION: return "firmware trapped: call stack exhausted";
    default: return "firmware trapped";
    }
}

static void throw_trap(JNIEnv *env, int code)
{
    const char *cls = code == TRAP_NO_MEMORY ? "java/lang/OutOfMemoryError" : "java/lang/IllegalStateException";
    const char *message = code == TRAP_NO_MEMORY ? "no memory for a firmware instance"
                          : code == TRAP_MEMORY_SIZE ? "the native engine was built for another memory size"
                                                     : trap_message(code);
    jclass c = (*env)->FindClass(env, cls);
    if (c != NULL)
        (*env)->ThrowNew(env, c, message);
}

/* Runs `call` with traps caught: a trap longjmps back here and is thrown as a Java exception. A local that `call`
 * sets is volatile (setjmp's rule), though after a trap only the exception counts. Calls in never nest: the depth
 * starts from 0 (a trap left it where it was). */
#define GUARDED(env, call)                                                                                             \
    do {                                                                                                               \
        jmp_buf guard;                                                                                                 \
        int trapped = setjmp(guard);                                                                                   \
        if (trapped == 0) {                                                                                            \
            trap_target = &guard;                                                                                      \
            engine_call_depth = 0;                                                                                     \
            call;                                                                                                      \
        } else {                                                                                                       \
            throw_trap(env, trapped);                                                                                  \
        }                                                                                                              \
        trap_target = NULL;                                                                                            \
    } while (0)

#define INSTANCE(handle) ((Z_pocketbot_instance_t *)(intptr_t)(handle))

JNIEXPORT jint JNICALL JNI_OnLoad(JavaVM *vm, void *reserved)
{
    (void)vm;
    (void)reserved;
    Z_pocketbot_init_module();
    return JNI_VERSION_1_8;
}

jstring EXPORT(wasmSha256)(JNIEnv *env, jclass cls)
{
    (void)cls;
    return (*env)->NewStringUTF(env, POCKETBOT_WASM_SHA256);
}

/* A fresh instance: memory with the data segments, globals and table initialised, as WebAssembly instantiation. */
jlong EXPORT(instantiate)(JNIEnv *env, jclass cls)
{
    (void)cls;
    Z_pocketbot_instance_t *instance = calloc(1, sizeof *instance);
    if (instance == NULL) {
        throw_trap(env, TRAP_NO_MEMORY);
        return 0;
    }
    GUARDED(env, Z_pocketbot_instantiate(instance));
    if ((*env)->ExceptionCheck(env)) {
        free(instance->w2c_memory.data); /* calloc'd: NULL when the failure came first */
        free(instance->w2c_T0.data);
        free(instance);
        return 0;
    }
    return (jlong)(intptr_t)instance;
}

void EXPORT(free)(JNIEnv *env, jclass cls, jlong handle)
{
    (void)env;
    (void)cls;
    Z_pocketbot_free(INSTANCE(handle));
    free(INSTANCE(handle));
}

/* The instance's linear memory as a direct buffer: valid until free (the memory never moves, see grow). */
jobject EXPORT(memory)(JNIEnv *env, jclass cls, jlong handle)
{
    (void)cls;
    wasm_rt_memory_t *m = &INSTANCE(handle)->w2c_memory;
    return (*env)->NewDirectByteBuffer(env, m->data, (jlong)m->size);
}

/* The exports of sim_abi.h that take nothing and return an int (the addresses, sim_links), numbered as
 * NativeEngine.ADDRESSES. */
jint EXPORT(address)(JNIEnv *env, jclass cls, jlong handle, jint which)
{
    (void)cls;
    Z_pocketbot_instance_t *i = INSTANCE(handle);
    volatile u32 a = UINT32_MAX;
    GUARDED(env, switch (which) {
        case 0: a = Z_pocketbotZ_sim_events(i); break;
        case 1: a = Z_pocketbotZ_sim_inputs(i); break;
        case 2: a = Z_pocketbotZ_sim_ir_out(i); break;
        case 3: a = Z_pocketbotZ_sim_outputs(i); break;
        case 4: a = Z_pocketbotZ_sim_state(i); break;
        case 5: a = Z_pocketbotZ_sim_settings(i); break;
        case 6: a = Z_pocketbotZ_sim_uart_tx_buffer(i); break;
        case 7: a = Z_pocketbotZ_sim_eeprom(i); break;
        case 8: a = Z_pocketbotZ_sim_links(i); break;
        default: break;
    });
    return (jint)a;
}

void EXPORT(init)(JNIEnv *env, jclass cls, jlong handle, jint robot_id)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_init(INSTANCE(handle), (u32)robot_id));
}

void EXPORT(advance)(JNIEnv *env, jclass cls, jlong handle, jlong now_ticks)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_advance(INSTANCE(handle), (u64)now_ticks));
}

void EXPORT(encoderEdge)(JNIEnv *env, jclass cls, jlong handle, jint wheel, jlong ticks)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_encoder_edge(INSTANCE(handle), (u32)wheel, (u64)ticks));
}

void EXPORT(uartRx)(JNIEnv *env, jclass cls, jlong handle, jint byte)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_uart_rx(INSTANCE(handle), (u32)byte));
}

void EXPORT(runEvents)(JNIEnv *env, jclass cls, jlong handle, jint count, jlong end_ticks)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_run_events(INSTANCE(handle), (u32)count, (u64)end_ticks));
}

jint EXPORT(uartTxTake)(JNIEnv *env, jclass cls, jlong handle, jint max)
{
    (void)cls;
    volatile u32 n = 0;
    GUARDED(env, n = Z_pocketbotZ_sim_uart_tx_take(INSTANCE(handle), (u32)max));
    return (jint)n;
}

jint EXPORT(linkTxTake)(JNIEnv *env, jclass cls, jlong handle, jint link, jint max)
{
    (void)cls;
    volatile u32 n = 0;
    GUARDED(env, n = Z_pocketbotZ_sim_link_tx_take(INSTANCE(handle), (u32)link, (u32)max));
    return (jint)n;
}

void EXPORT(irRx)(JNIEnv *env, jclass cls, jlong handle, jint side, jint sender, jint led, jint power, jint len,
                  jint lo, jint hi)
{
    (void)cls;
    GUARDED(env, Z_pocketbotZ_sim_ir_rx(INSTANCE(handle), (u32)side, (u32)sender, (u32)led, (u32)power, (u32)len,
                                        (u32)lo, (u32)hi));
}
