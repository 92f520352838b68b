// Depth of field: the 1-D multiply-accumulate of the separable layered convolution, one
// output sample of a pass per clock (src/stage/dof/fixed.rs `row_mac`, `border_sum`).
//
// dof_row_mac holds the coefficient ROM (one centred TAPS-entry set per layer, loaded with
// $readmemh from the Rust model's dof_rom.hex) and the two passes:
//   h_*: horizontal pass, image plane -> line buffer (saturated to H_OUT_BITS = dof.line_bits)
//   v_*: vertical pass, line buffer -> accumulator (saturated to V_OUT_BITS = dof.acc_bits)
// Each pass takes a window of TAPS = 2 HALF + 1 samples of the colour plane (x, premultiplied
// intensity), of the alpha plane (a, coverage share) and of the behind plane (d, the share of
// the layer and every layer behind it: the alpha's normaliser with dof.alpha_norm = "behind",
// the pixel's whole share with "image"); window sample t sits at line
// position pos + t - HALF. Taps outside the line (not 0 <= pos + t - HALF < len) are gated
// to zero whatever their inputs hold (the zero padding of the image border). Outputs:
//   sx  = min(sum c_t x_t, 2^OUT_BITS - 1), ovf = the sum did not fit (the Rust model counts
//         it; with dof.overflow = ERROR it stops the run),
//   sa  = sum c_t a_t (exact: SA_BITS = A_BITS + f, the taps sum to 2^f),
//   sd  = sum c_t d_t (exact, as sa): after both passes the alpha is A / D,
//   w   = sum of c_t over the in-line taps: the border renormalisation weight (Wx or Wy of
//         alpha normalisation a = A / (n^2 Wx Wy) of dof.alpha_norm = "image").
// Timing: tap-parallel (TAPS multipliers per plane and pass, adder tree): dof_mac_1d is
// combinational; dof_row_mac takes both passes' windows with one valid/ready handshake
// (hs_pipe.v) and carries both passes' outputs through LATENCY register stages (the preset's
// [cycles.dof] latency, 8; synthesis may retime them into the multipliers and the adder
// tree): one output sample per pass per clock, so one instance is the preset's two lanes.
module dof_mac_1d #(
    parameter HALF     = 4,
    parameter C_BITS   = 13,
    parameter POS_BITS = 10,
    parameter X_BITS   = 16,
    parameter A_BITS   = 5,
    parameter OUT_BITS = 32,
    parameter SA_BITS  = 17
) (
    input  wire [(2*HALF+1)*C_BITS-1:0] coef,
    input  wire [POS_BITS-1:0]          pos,
    input  wire [POS_BITS-1:0]          len,
    input  wire [(2*HALF+1)*X_BITS-1:0] x,
    input  wire [(2*HALF+1)*A_BITS-1:0] a,
    input  wire [(2*HALF+1)*A_BITS-1:0] d,
    output wire [OUT_BITS-1:0]          sx,
    output wire                         ovf,
    output wire [SA_BITS-1:0]           sa,
    output wire [SA_BITS-1:0]           sd,
    output wire [C_BITS-1:0]            w
);
    localparam TAPS = 2 * HALF + 1;
    // A layer's taps sum to 2^f < 2^C_BITS, so the exact sum fits X_BITS + C_BITS bits.
    localparam S_BITS = (X_BITS + C_BITS > OUT_BITS) ? X_BITS + C_BITS : OUT_BITS + 1;
    localparam [S_BITS-1:0] MAX = {{(S_BITS-OUT_BITS){1'b0}}, {OUT_BITS{1'b1}}};
    reg [S_BITS-1:0]  sum_x;
    reg [SA_BITS-1:0] sum_a;
    reg [SA_BITS-1:0] sum_d;
    reg [C_BITS-1:0]  sum_w;
    integer t;
    always @* begin
        sum_x = 0;
        sum_a = 0;
        sum_d = 0;
        sum_w = 0;
        for (t = 0; t < TAPS; t = t + 1) begin
            if (pos + t >= HALF && pos + t < len + HALF) begin
                sum_x = sum_x + x[t*X_BITS +: X_BITS] * coef[t*C_BITS +: C_BITS];
                sum_a = sum_a + a[t*A_BITS +: A_BITS] * coef[t*C_BITS +: C_BITS];
                sum_d = sum_d + d[t*A_BITS +: A_BITS] * coef[t*C_BITS +: C_BITS];
                sum_w = sum_w + coef[t*C_BITS +: C_BITS];
            end
        end
    end
    assign ovf = sum_x > MAX;
    assign sx  = (sum_x > MAX) ? {OUT_BITS{1'b1}} : sum_x[OUT_BITS-1:0];
    assign sa  = sum_a;
    assign sd  = sum_d;
    assign w   = sum_w;
endmodule

module dof_row_mac #(
    parameter HALF       = 4,
    parameter LAYERS     = 1,
    parameter LAYER_BITS = 1,
    parameter C_BITS     = 13,
    parameter POS_BITS   = 10,
    parameter HX_BITS    = 16,
    parameter HA_BITS    = 5,
    parameter H_OUT_BITS = 28,
    parameter H_SA_BITS  = 17,
    parameter VX_BITS    = 28,
    parameter VA_BITS    = 17,
    parameter V_OUT_BITS = 40,
    parameter V_SA_BITS  = 29,
    parameter ROM_FILE   = "dof_rom.hex",
    parameter LATENCY    = 8
) (
    input  wire                          clk,
    input  wire                          rst,
    input  wire                          in_valid,
    output wire                          in_ready,
    output wire                          out_valid,
    input  wire                          out_ready,
    input  wire [LAYER_BITS-1:0]         h_layer,
    input  wire [POS_BITS-1:0]           h_pos,
    input  wire [POS_BITS-1:0]           h_len,
    input  wire [(2*HALF+1)*HX_BITS-1:0] h_x,
    input  wire [(2*HALF+1)*HA_BITS-1:0] h_a,
    input  wire [(2*HALF+1)*HA_BITS-1:0] h_d,
    output wire [H_OUT_BITS-1:0]         h_sx,
    output wire                          h_ovf,
    output wire [H_SA_BITS-1:0]          h_sa,
    output wire [H_SA_BITS-1:0]          h_sd,
    output wire [C_BITS-1:0]             h_w,
    input  wire [LAYER_BITS-1:0]         v_layer,
    input  wire [POS_BITS-1:0]           v_pos,
    input  wire [POS_BITS-1:0]           v_len,
    input  wire [(2*HALF+1)*VX_BITS-1:0] v_x,
    input  wire [(2*HALF+1)*VA_BITS-1:0] v_a,
    input  wire [(2*HALF+1)*VA_BITS-1:0] v_d,
    output wire [V_OUT_BITS-1:0]         v_sx,
    output wire                          v_ovf,
    output wire [V_SA_BITS-1:0]          v_sa,
    output wire [V_SA_BITS-1:0]          v_sd,
    output wire [C_BITS-1:0]             v_w
);
    localparam TAPS = 2 * HALF + 1;
    reg [C_BITS-1:0] rom [0:LAYERS*TAPS-1];
    initial $readmemh(ROM_FILE, rom);
    // Asynchronous read of the layer's TAPS coefficients (a per-layer coefficient bank).
    wire [TAPS*C_BITS-1:0] h_coef, v_coef;
    genvar g;
    generate
        for (g = 0; g < TAPS; g = g + 1) begin : g_rom
            assign h_coef[g*C_BITS +: C_BITS] = rom[h_layer*TAPS + g];
            assign v_coef[g*C_BITS +: C_BITS] = rom[v_layer*TAPS + g];
        end
    endgenerate
    // Both passes' outputs before the pipeline.
    localparam H_W = H_OUT_BITS + 1 + 2 * H_SA_BITS + C_BITS;
    localparam V_W = V_OUT_BITS + 1 + 2 * V_SA_BITS + C_BITS;
    wire [H_W-1:0] h_next;
    wire [V_W-1:0] v_next;
    dof_mac_1d #(.HALF(HALF), .C_BITS(C_BITS), .POS_BITS(POS_BITS), .X_BITS(HX_BITS),
                 .A_BITS(HA_BITS), .OUT_BITS(H_OUT_BITS), .SA_BITS(H_SA_BITS))
        u_h (.coef(h_coef), .pos(h_pos), .len(h_len), .x(h_x), .a(h_a), .d(h_d),
             .sx(h_next[H_W-1 -: H_OUT_BITS]), .ovf(h_next[H_W-1-H_OUT_BITS]),
             .sa(h_next[C_BITS+H_SA_BITS +: H_SA_BITS]), .sd(h_next[C_BITS +: H_SA_BITS]),
             .w(h_next[C_BITS-1:0]));
    dof_mac_1d #(.HALF(HALF), .C_BITS(C_BITS), .POS_BITS(POS_BITS), .X_BITS(VX_BITS),
                 .A_BITS(VA_BITS), .OUT_BITS(V_OUT_BITS), .SA_BITS(V_SA_BITS))
        u_v (.coef(v_coef), .pos(v_pos), .len(v_len), .x(v_x), .a(v_a), .d(v_d),
             .sx(v_next[V_W-1 -: V_OUT_BITS]), .ovf(v_next[V_W-1-V_OUT_BITS]),
             .sa(v_next[C_BITS+V_SA_BITS +: V_SA_BITS]), .sd(v_next[C_BITS +: V_SA_BITS]),
             .w(v_next[C_BITS-1:0]));
    hs_pipe #(.W(H_W + V_W), .DEPTH(LATENCY)) u_pipe (
        .clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
        .in_data({h_next, v_next}), .out_valid(out_valid), .out_ready(out_ready),
        .out_data({h_sx, h_ovf, h_sa, h_sd, h_w, v_sx, v_ovf, v_sa, v_sd, v_w}));
endmodule
