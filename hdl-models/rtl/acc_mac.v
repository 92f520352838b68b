// Accumulate: one I*S term into the accumulating word, and that word's clamp to the frame.
// part = round(w * i / 2^SHIFT) (SHIFT < 0: shift left), acc_out = acc_in + part with the
// overflow mode; ovf flags an overflow.
// SIGNED = 0 (box, tent, Gaussian, B-spline): w, i, acc_in unsigned; the accumulating word
// is the frame word (A_BITS = F_BITS); clamp_out = acc_out, clamp_ovf = 0.
// SIGNED = 1 (Catmull-Rom, Mitchell: negative lobes): w is a W_BITS two's-complement weight,
// i unsigned, acc_in / acc_out the A_BITS two's-complement accumulator (its sign and
// headroom bits derived from the kernel); clamp_out is acc_out clamped to the unsigned
// F_BITS frame word with the overflow mode (clamp_ovf flags it): the pixel's last term.
// QUANT: 0 floor (TRN; TRN_ZERO for unsigned), 1 ties up (RND; RND_INF for unsigned),
// 2 ties down (RND_MIN_INF; RND_ZERO for unsigned), 3 ties to even (RND_CONV),
// 4 toward zero (TRN_ZERO), 5 ties away from zero (RND_INF), 6 ties toward zero (RND_ZERO).
// OVF: 0 wrap, 1 saturate to the limits (SAT, ERROR; SAT_SYM for unsigned), 2 saturate to
// zero, 3 symmetric saturation of the signed accumulator (SAT_SYM: -max for the minimum
// too, flagged); the clamp to the unsigned frame word treats 3 as 1.
// Timing: valid/ready handshake (hs_pipe.v), the multiply/round/add/clamp datapath followed
// by LATENCY register stages (the preset's [cycles.accumulate] latency, 6; synthesis may
// retime them into the multiplier and adders), one term per clock per instance (one lane).
module acc_mac #(
    parameter W_BITS = 10,
    parameter I_BITS = 16,
    parameter F_BITS = 12,
    parameter SHIFT  = 14,
    parameter QUANT  = 3,
    parameter OVF    = 1,
    parameter SIGNED = 0,
    parameter A_BITS = F_BITS,
    parameter LATENCY = 6
) (
    input  wire              clk,
    input  wire              rst,
    input  wire              in_valid,
    output wire              in_ready,
    output wire              out_valid,
    input  wire              out_ready,
    input  wire [W_BITS-1:0] w,
    input  wire [I_BITS-1:0] i,
    input  wire [A_BITS-1:0] acc_in,
    output wire [A_BITS-1:0] acc_out,
    output wire              ovf,
    output wire [F_BITS-1:0] clamp_out,
    output wire              clamp_ovf
);
    localparam P_BITS = W_BITS + I_BITS + 1;
    localparam LSH    = (SHIFT < 0) ? -SHIFT : 0;
    localparam S_BITS = P_BITS + LSH + A_BITS + 2;
    // The product and everything after it in two's complement of S_BITS (the unsigned
    // operands zero-extended).
    wire signed [W_BITS:0]   ws = SIGNED ? {w[W_BITS-1], w} : {1'b0, w};
    wire signed [I_BITS:0]   is = {1'b0, i};
    wire signed [S_BITS-1:0] p  = ws * is;
    wire signed [S_BITS-1:0] part;
    generate
        if (SHIFT > 0) begin : g_round
            wire signed [S_BITS-1:0] one  = 1;
            wire signed [S_BITS-1:0] half = one <<< (SHIFT - 1);
            wire signed [S_BITS-1:0] rem  = p & ((half <<< 1) - one);
            wire signed [S_BITS-1:0] fl   = p >>> SHIFT;
            wire neg  = p < 0;
            wire fneg = fl < 0;
            wire nz   = rem != 0;
            wire tie  = rem == half;
            wire gt   = rem > half;
            wire up = !nz ? 1'b0 :
                      (QUANT == 0) ? 1'b0 :
                      (QUANT == 4) ? neg :
                      !tie ? gt :
                      (QUANT == 1) ? 1'b1 :
                      (QUANT == 2) ? 1'b0 :
                      (QUANT == 3) ? fl[0] :
                      (QUANT == 5) ? !fneg : fneg;
            assign part = fl + up;
        end else begin : g_shl
            assign part = p <<< LSH;
        end
    endgenerate
    wire signed [S_BITS-1:0] a_in = SIGNED ? {{(S_BITS-A_BITS){acc_in[A_BITS-1]}}, acc_in}
                                           : {{(S_BITS-A_BITS){1'b0}}, acc_in};
    wire signed [S_BITS-1:0] sum  = part + a_in;
    wire signed [S_BITS-1:0] one_s = 1;
    wire signed [S_BITS-1:0] amax = SIGNED ? (one_s <<< (A_BITS - 1)) - one_s
                                           : (one_s <<< A_BITS) - one_s;
    wire signed [S_BITS-1:0] amin = SIGNED ? -(one_s <<< (A_BITS - 1)) : 0;
    wire signed [S_BITS-1:0] nmax = -amax;
    wire over  = (sum > amax) || (sum < amin) || (SIGNED && OVF == 3 && sum == amin);
    wire [A_BITS-1:0] acc_next = !over ? sum[A_BITS-1:0] :
                                 (OVF == 0) ? sum[A_BITS-1:0] :
                                 (OVF == 1) ? ((sum > amax) ? amax[A_BITS-1:0] : amin[A_BITS-1:0]) :
                                 (OVF == 3) ? ((sum > amax) ? amax[A_BITS-1:0] : nmax[A_BITS-1:0]) :
                                 {A_BITS{1'b0}};
    // The clamp of the new accumulator to the unsigned frame word.
    wire signed [S_BITS-1:0] a_next = SIGNED ? {{(S_BITS-A_BITS){acc_next[A_BITS-1]}}, acc_next}
                                             : {{(S_BITS-A_BITS){1'b0}}, acc_next};
    wire signed [S_BITS-1:0] fmax = (one_s <<< F_BITS) - one_s;
    wire c_over = SIGNED && ((a_next > fmax) || (a_next < 0));
    wire [F_BITS-1:0] c_next = !c_over ? a_next[F_BITS-1:0] :
                               (OVF == 0) ? a_next[F_BITS-1:0] :
                               (OVF == 1 || OVF == 3) ? ((a_next > fmax) ? {F_BITS{1'b1}} : {F_BITS{1'b0}}) :
                               {F_BITS{1'b0}};
    hs_pipe #(.W(A_BITS + F_BITS + 2), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
        .in_data({over, acc_next, c_over, c_next}), .out_valid(out_valid),
        .out_ready(out_ready), .out_data({ovf, acc_out, clamp_ovf, clamp_out}));
endmodule
