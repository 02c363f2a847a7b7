/* dump_module_blob.S - the image module (wall/dump_module.h) embedded in the executable:
 * the bytes of the shared object named by TESS_DUMP_MODULE_FILE (the Makefile passes the
 * file its tree built), between tess_dump_module_start and tess_dump_module_end, read only;
 * wall/dump.c loads them. */
    .section .rodata.tess_dump_module, "a"
    .balign 64
    .globl tess_dump_module_start
    .globl tess_dump_module_end
    .hidden tess_dump_module_start
    .hidden tess_dump_module_end
tess_dump_module_start:
    .incbin TESS_DUMP_MODULE_FILE
tess_dump_module_end:
    .section .note.GNU-stack, "", @progbits
