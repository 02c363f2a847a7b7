/* source.c - what every input source shares (source.h). */
#include "source.h"

void input_area_point(const camera_window *a, double fx, double fy, double *sx, double *sy)
{
    *sx = (double)a->center_x + (2.0 * fx - 1.0) * (double)a->half_width;
    *sy = (double)a->center_y - (2.0 * fy - 1.0) * (double)a->half_height;
}
