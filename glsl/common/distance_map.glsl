// Chebyshev distance maps over the cell grid, shared by the build passes and
// the march. Every cell holds byte distances in "channels": the first half
// to the nearest active cell (0 in active cells), the second half to the
// nearest empty cell (0 in empty cells), so a ray crosses a whole empty cube
// or a whole active cube in one step. One channel per half for cube maps; with
// OCTANTS, one per ray direction octant (bit a set = negative along axis a),
// counting only cells ahead of such a ray. The includer defines OCTANTS.
#ifndef LACUNA_DISTANCE_MAP_GLSL
#define LACUNA_DISTANCE_MAP_GLSL

// Largest stored distance (a byte): a cap only shortens jumps.
#define DISTANCE_CAP 255u
#define DISTANCE_CHANNELS (OCTANTS != 0u ? 16u : 2u)
#define DISTANCE_WORDS (OCTANTS != 0u ? 4u : 1u)

// Channel of the distance to the nearest cell of the other kind, for a cell
// that is active or not, seen by a ray of `octant`.
uint distance_channel(bool is_active, uint octant) {
    return (is_active ? DISTANCE_CHANNELS / 2u : 0u) + (OCTANTS != 0u ? octant : 0u);
}

uint distance_byte(uint word, uint channel) {
    return (word >> (8u * (channel & 3u))) & 255u;
}

#endif
