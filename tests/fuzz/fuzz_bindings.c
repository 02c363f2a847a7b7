/* fuzz_bindings.c - bindings files (input/bindings.c) through
 * input_bindings_parse. Parsed bindings must name only known actions, and the
 * quit chord must be within its slots with the rest zero. */
#include "fuzz.h"

#include <string.h>

#include "input/bindings.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *name = "bindings.json";
    input_bindings b, before;
    memset(&b, 0xA5, sizeof b);
    before = b;
    tess_error err = {{0}};
    if (!input_bindings_parse(name, (const char *)data, size, &b, &err)) {
        fuzz_check_error(&err, name);
        if (memcmp(&b, &before, sizeof b) != 0)
            fuzz_fail("%s: a failed parse changed the bindings", name);
        return 0;
    }
    for (size_t i = 0; i < INPUT_CODE_COUNT; i++)
        if (b.code_action[i] >= INPUT_ACTION_COUNT)
            fuzz_fail("%s: code 0x%zx: action %u", name, i, b.code_action[i]);
    for (size_t i = 0; i < INPUT_GESTURE_COUNT; i++)
        if (b.gesture_action[i] >= INPUT_ACTION_COUNT)
            fuzz_fail("%s: gesture %zu: action %u", name, i, b.gesture_action[i]);
    if (b.quit_chord_len < 0 || b.quit_chord_len > INPUT_CHORD_MAX)
        fuzz_fail("%s: quit chord of %d keys", name, b.quit_chord_len);
    for (int i = 0; i < INPUT_CHORD_MAX; i++)
        if (i < b.quit_chord_len ? (b.quit_chord[i] <= 0 || b.quit_chord[i] >= INPUT_CODE_COUNT) : b.quit_chord[i] != 0)
            fuzz_fail("%s: quit chord slot %d is %d", name, i, b.quit_chord[i]);
    return 0;
}
