/* txn_private.h - what the record files share (txn.c, txn_apply.c,
 * txn_text.c, txn_binary.c) and nothing else includes. */
#ifndef TESSERA_FRAME_TXN_PRIVATE_H
#define TESSERA_FRAME_TXN_PRIVATE_H

/* |n| in double: exact squares of floats (no overflow or underflow to 0 for
 * any finite nonzero n). What validation and apply both measure a clip
 * plane's normal by. */
double txn_normal_length(const float n[3]);

#endif
