/*
 * Embeds the cross-architecture test vector (targets/cortex-m4f/vector/frames.bin) in flash,
 * 4-byte aligned so that main.c reads its depth images as float arrays in place (no copy).
 * The build passes the vector's directory to the assembler: -Wa,-I,<dir>.
 */
	.section .rodata.sndt_vector, "a", %progbits
	.balign 4
	.global sndt_vector
	.type sndt_vector, %object
sndt_vector:
	.incbin "frames.bin"
	.global sndt_vector_end
sndt_vector_end:
	.size sndt_vector, sndt_vector_end - sndt_vector

	/* Tell the linker this object needs no executable stack. */
	.section .note.GNU-stack, "", %progbits
