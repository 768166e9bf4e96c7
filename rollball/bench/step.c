/* The RK4 Munthe-Kaas step of rollball.kernel, written by hand in C for the hills landscape
   f = 0.5 sin(x) cos(y): the yardstick for the compiled kernel's speed (`rollball bench`).

   Same algorithm, same monitoring: four evaluations a step (the first reused from the previous
   step's end), Rodrigues update of R, non-finite check, fit check r*kappa < 1, normal force and
   lift-off detection, a recorded row every EVERY steps.

   Usage: step R M G X Y DT STEPS  ->  prints "ns_per_step x y" */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <time.h>

#define EVERY 100

static double r, m, g0, k, mr, mr2, mg;   /* k = 5/(7 m r^2), mr = m r, mr2 = m r^2, mg = m g0 */

/* derivative of (x, y, v, u); with probe, also normal force and r*kappa */
static inline void dyn(const double *z, double *dz, int probe, double *force, double *fit) {
    double sx = sin(z[0]), cx = cos(z[0]), sy = sin(z[1]), cy = cos(z[1]);
    double fx = 0.5 * cx * cy, fy = -0.5 * sx * sy;
    double fxx = -0.5 * sx * cy, fxy = -0.5 * cx * sy, fyy = fxx;
    double W2 = 1.0 + fx * fx + fy * fy, iW = 1.0 / sqrt(W2);
    double n1 = -fx * iW, n2 = -fy * iW, n3 = iW;
    double nv = 2.5 * (n1 * z[2] + n2 * z[3] + n3 * z[4]);
    double o1 = k * (z[2] + nv * n1), o2 = k * (z[3] + nv * n2), o3 = k * (z[4] + nv * n3);
    double s = n1 * fxx + n2 * fxy;
    double Nx1 = (n1 * s - fxx) * iW, Nx2 = (n2 * s - fxy) * iW, Nx3 = n3 * s * iW;
    s = n1 * fxy + n2 * fyy;
    double Ny1 = (n1 * s - fxy) * iW, Ny2 = (n2 * s - fyy) * iW, Ny3 = n3 * s * iW;
    double Cx1 = 1.0 + r * Nx1, Cx2 = r * Nx2, Cx3 = fx + r * Nx3;
    double Cy1 = r * Ny1, Cy2 = 1.0 + r * Ny2, Cy3 = fy + r * Ny3;
    double E11 = Cx1 * Cx1 + Cx2 * Cx2 + Cx3 * Cx3;
    double E12 = Cx1 * Cy1 + Cx2 * Cy2 + Cx3 * Cy3;
    double E22 = Cy1 * Cy1 + Cy2 * Cy2 + Cy3 * Cy3;
    double idet = 1.0 / (E11 * E22 - E12 * E12);
    double w1 = o2 * n3 - o3 * n2, w2 = o3 * n1 - o1 * n3, w3 = o1 * n2 - o2 * n1;
    double b1 = r * (Cx1 * w1 + Cx2 * w2 + Cx3 * w3), b2 = r * (Cy1 * w1 + Cy2 * w2 + Cy3 * w3);
    double a1 = (E22 * b1 - E12 * b2) * idet, a2 = (E11 * b2 - E12 * b1) * idet;
    double d1 = Nx1 * a1 + Ny1 * a2, d2 = Nx2 * a1 + Ny2 * a2, d3 = Nx3 * a1 + Ny3 * a2;
    dz[0] = a1;
    dz[1] = a2;
    dz[2] = -mg * r * n2 + mr2 * (d2 * w3 - d3 * w2);
    dz[3] = mg * r * n1 + mr2 * (d3 * w1 - d1 * w3);
    dz[4] = mr2 * (d1 * w2 - d2 * w1);
    double u1 = z[5], u2 = z[6], u3 = z[7];
    double c1 = u2 * o3 - u3 * o2, c2 = u3 * o1 - u1 * o3, c3 = u1 * o2 - u2 * o1;
    dz[5] = o1 - 0.5 * c1 + (u2 * c3 - u3 * c2) * (1.0 / 12.0);
    dz[6] = o2 - 0.5 * c2 + (u3 * c1 - u1 * c3) * (1.0 / 12.0);
    dz[7] = o3 - 0.5 * c3 + (u1 * c2 - u2 * c1) * (1.0 / 12.0);
    if (probe) {
        *force = mr * ((o2 * d3 - o3 * d2) * n1 + (o3 * d1 - o1 * d3) * n2 + (o1 * d2 - o2 * d1) * n3)
                 + mg * n3;
        double G11 = 1.0 + fx * fx, G12 = fx * fy, G22 = 1.0 + fy * fy;
        double h11 = fxx * iW, h12 = fxy * iW, h22 = fyy * iW, iW2 = iW * iW;
        double mean = 0.5 * (G11 * h22 + G22 * h11 - 2.0 * G12 * h12) * iW2;
        double gauss = (h11 * h22 - h12 * h12) * iW2;
        *fit = r * (mean + sqrt(fmax(mean * mean - gauss, 0.0)));
    }
}

int main(int argc, char **argv) {
    if (argc != 8) { fprintf(stderr, "usage: step R M G X Y DT STEPS\n"); return 2; }
    r = atof(argv[1]); m = atof(argv[2]); g0 = atof(argv[3]);
    k = 5.0 / (7.0 * m * r * r); mr = m * r; mr2 = m * r * r; mg = m * g0;
    double h = atof(argv[6]);
    long n = atol(argv[7]);
    double z[8] = {atof(argv[4]), atof(argv[5]), 0, 0, 0, 0, 0, 0};
    double R[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double *rows = malloc(sizeof(double) * 12 * (n / EVERY + 2));
    double k0[8], k1[8], k2[8], k3[8], y[8], force, fit, prev, liftoff = NAN;
    dyn(z, k0, 1, &prev, &fit);
    struct timespec t0, t1;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    long step;
    for (step = 1; step <= n; step++) {
        for (int q = 0; q < 8; q++) y[q] = z[q] + h * 0.5 * k0[q];
        dyn(y, k1, 0, 0, 0);
        for (int q = 0; q < 8; q++) y[q] = z[q] + h * 0.5 * k1[q];
        dyn(y, k2, 0, 0, 0);
        for (int q = 0; q < 8; q++) y[q] = z[q] + h * k2[q];
        dyn(y, k3, 0, 0, 0);
        double zn[8];
        for (int q = 0; q < 8; q++) zn[q] = z[q] + h * (k0[q] + 2.0 * k1[q] + 2.0 * k2[q] + k3[q]) / 6.0;
        /* R <- exp(A(u)) R */
        double u1 = zn[5], u2 = zn[6], u3 = zn[7], th2 = u1 * u1 + u2 * u2 + u3 * u3, th = sqrt(th2), a, b;
        if (th < 1e-4) {
            a = 1.0 - th2 / 6.0 * (1.0 - th2 / 20.0);
            b = 0.5 - th2 / 24.0 * (1.0 - th2 / 30.0);
        } else {
            double hs = sin(0.5 * th) / th;
            a = sin(th) / th;
            b = 2.0 * hs * hs;
        }
        double Q[9] = {1.0 + b * (u1 * u1 - th2), -a * u3 + b * u1 * u2, a * u2 + b * u1 * u3,
                       a * u3 + b * u1 * u2, 1.0 + b * (u2 * u2 - th2), -a * u1 + b * u2 * u3,
                       -a * u2 + b * u1 * u3, a * u1 + b * u2 * u3, 1.0 + b * (u3 * u3 - th2)};
        double Rn[9];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++)
                Rn[3 * i + j] = Q[3 * i] * R[j] + Q[3 * i + 1] * R[3 + j] + Q[3 * i + 2] * R[6 + j];
        zn[5] = zn[6] = zn[7] = 0.0;
        dyn(zn, k0, 1, &force, &fit);
        double check = 0.0;
        for (int q = 0; q < 5; q++) check += zn[q] * 0.0 + k0[q] * 0.0;
        for (int q = 0; q < 9; q++) check += Rn[q] * 0.0;
        if (check != 0.0 || force != force || fit != fit) break;   /* non-finite */
        if (fit >= 1.0) break;                                      /* does not fit */
        if (force <= 0.0 && prev > 0.0 && liftoff != liftoff)
            liftoff = step * h - h + h * prev / (prev - force);
        prev = force;
        for (int q = 0; q < 8; q++) z[q] = zn[q];
        for (int q = 0; q < 9; q++) R[q] = Rn[q];
        if (step % EVERY == 0) {
            double *row = rows + 12 * (step / EVERY);
            row[0] = step * h; row[1] = z[0]; row[2] = z[1];
            for (int q = 0; q < 9; q++) row[3 + q] = R[q];
        }
    }
    clock_gettime(CLOCK_MONOTONIC, &t1);
    double ns = (t1.tv_sec - t0.tv_sec) * 1e9 + (t1.tv_nsec - t0.tv_nsec);
    printf("%.6g %.17g %.17g\n", ns / (double)(step - 1), z[0], z[1]);
    free(rows);
    return step - 1 == n ? 0 : 1;
}
