/* A minimal FMI co-simulation importer for the tests (issue 38 item 1): loads an FMU's
 * binary (LoadLibrary on Windows, dlopen elsewhere), runs the table-speed ramp
 * v(t) = v_end * min(t / ramp, 1) for `stop` seconds in communication steps of `h` and
 * prints the table position after every step ("%.17g").  Built natively for the linux64
 * binary and with MinGW-w64 for the win64 DLL (run under Wine): the same importer, the same
 * inputs, so the two traces compare the binaries only.  FMI_VERSION 2 or 3 at compile time.
 *
 * usage: harness LIBRARY TOKEN VR_SPEED VR_POSITION V_END RAMP H STOP
 */
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#if FMI_VERSION == 2
#include "fmi2Functions.h"
#else
#include "fmi3Functions.h"
#endif

#ifdef _WIN32
#include <windows.h>
static void *open_library(const char *path) { return (void *)LoadLibraryA(path); }
static void *symbol(void *lib, const char *name) {
    return (void *)GetProcAddress((HMODULE)lib, name);
}
#else
#include <dlfcn.h>
static void *open_library(const char *path) { return dlopen(path, RTLD_NOW | RTLD_LOCAL); }
static void *symbol(void *lib, const char *name) { return dlsym(lib, name); }
#endif

#define LOAD(TYPE, NAME)                                                       \
    TYPE NAME = (TYPE)symbol(lib, #NAME);                                      \
    if (!NAME) {                                                               \
        fprintf(stderr, "missing %s\n", #NAME);                                \
        return 3;                                                              \
    }

#if FMI_VERSION == 2
static void logger(fmi2ComponentEnvironment env, fmi2String name, fmi2Status status,
                   fmi2String category, fmi2String message, ...) {
    va_list args;
    (void)env; (void)name; (void)category;
    va_start(args, message);
    fprintf(stderr, "[%d] ", (int)status);
    vfprintf(stderr, message, args);
    fprintf(stderr, "\n");
    va_end(args);
}
#else
static void logger(fmi3InstanceEnvironment env, fmi3Status status, fmi3String category,
                   fmi3String message) {
    (void)env; (void)category;
    fprintf(stderr, "[%d] %s\n", (int)status, message);
}
#endif

int main(int argc, char **argv) {
    void *lib;
    const char *token;
    unsigned int vr_speed, vr_position;
    double v_end, ramp, h, stop, t = 0.0, v, x;
    long k, n;
    if (argc != 9) {
        fprintf(stderr, "usage: harness LIBRARY TOKEN VR_SPEED VR_POSITION V_END RAMP H STOP\n");
        return 2;
    }
    lib = open_library(argv[1]);
    if (!lib) {
#ifdef _WIN32
        fprintf(stderr, "cannot load %s (error %lu)\n", argv[1], (unsigned long)GetLastError());
#else
        fprintf(stderr, "cannot load %s: %s\n", argv[1], dlerror());
#endif
        return 3;
    }
    token = argv[2];
    vr_speed = (unsigned int)strtoul(argv[3], NULL, 10);
    vr_position = (unsigned int)strtoul(argv[4], NULL, 10);
    v_end = strtod(argv[5], NULL);
    ramp = strtod(argv[6], NULL);
    h = strtod(argv[7], NULL);
    stop = strtod(argv[8], NULL);
    n = (long)(stop / h + 0.5);
    {
#if FMI_VERSION == 2
        fmi2CallbackFunctions cb = {logger, calloc, free, NULL, NULL};
        fmi2Component c;
        fmi2ValueReference vs = vr_speed, vx = vr_position;
        LOAD(fmi2InstantiateTYPE *, fmi2Instantiate)
        LOAD(fmi2SetupExperimentTYPE *, fmi2SetupExperiment)
        LOAD(fmi2EnterInitializationModeTYPE *, fmi2EnterInitializationMode)
        LOAD(fmi2ExitInitializationModeTYPE *, fmi2ExitInitializationMode)
        LOAD(fmi2SetRealTYPE *, fmi2SetReal)
        LOAD(fmi2GetRealTYPE *, fmi2GetReal)
        LOAD(fmi2DoStepTYPE *, fmi2DoStep)
        LOAD(fmi2FreeInstanceTYPE *, fmi2FreeInstance)
        c = fmi2Instantiate("harness", fmi2CoSimulation, token, "", &cb, fmi2False, fmi2False);
        if (!c) return 4;
        if (fmi2SetupExperiment(c, fmi2False, 0.0, 0.0, fmi2False, 0.0) != fmi2OK) return 5;
        if (fmi2EnterInitializationMode(c) != fmi2OK) return 5;
        if (fmi2ExitInitializationMode(c) != fmi2OK) return 5;
        fmi2GetReal(c, &vx, 1, &x);
        printf("%.17g\n", x);
        for (k = 0; k < n; k++) {
            t = k * h;
            v = v_end * (ramp > 0.0 && t < ramp ? t / ramp : 1.0);
            if (fmi2SetReal(c, &vs, 1, &v) != fmi2OK) return 6;
            if (fmi2DoStep(c, t, h, fmi2True) != fmi2OK) return 7;
            fmi2GetReal(c, &vx, 1, &x);
            printf("%.17g\n", x);
        }
        fmi2FreeInstance(c);
#else
        fmi3Instance c;
        fmi3ValueReference vs = vr_speed, vx = vr_position;
        fmi3Boolean event, terminate, early;
        fmi3Float64 last;
        LOAD(fmi3InstantiateCoSimulationTYPE *, fmi3InstantiateCoSimulation)
        LOAD(fmi3EnterInitializationModeTYPE *, fmi3EnterInitializationMode)
        LOAD(fmi3ExitInitializationModeTYPE *, fmi3ExitInitializationMode)
        LOAD(fmi3SetFloat64TYPE *, fmi3SetFloat64)
        LOAD(fmi3GetFloat64TYPE *, fmi3GetFloat64)
        LOAD(fmi3DoStepTYPE *, fmi3DoStep)
        LOAD(fmi3FreeInstanceTYPE *, fmi3FreeInstance)
        c = fmi3InstantiateCoSimulation("harness", token, "", fmi3False, fmi3False, fmi3False,
                                        fmi3False, NULL, 0, NULL, logger, NULL);
        if (!c) return 4;
        if (fmi3EnterInitializationMode(c, fmi3False, 0.0, 0.0, fmi3False, 0.0) != fmi3OK)
            return 5;
        if (fmi3ExitInitializationMode(c) != fmi3OK) return 5;
        fmi3GetFloat64(c, &vx, 1, &x, 1);
        printf("%.17g\n", x);
        for (k = 0; k < n; k++) {
            t = k * h;
            v = v_end * (ramp > 0.0 && t < ramp ? t / ramp : 1.0);
            if (fmi3SetFloat64(c, &vs, 1, &v, 1) != fmi3OK) return 6;
            if (fmi3DoStep(c, t, h, fmi3True, &event, &terminate, &early, &last) != fmi3OK)
                return 7;
            fmi3GetFloat64(c, &vx, 1, &x, 1);
            printf("%.17g\n", x);
        }
        fmi3FreeInstance(c);
#endif
    }
    return 0;
}
