// Self-checking testbench of dof_row_mac. Fields per vector (TAPS = 2 HALF + 1):
// pass (0 horizontal, 1 vertical), layer, pos, len, x[0..TAPS-1], a[0..TAPS-1],
// d[0..TAPS-1], expected sx, ovf, sa, sd, w. A vector drives both passes' inputs; its pass selects the
// outputs compared. The vectors stream through the handshake (hs_tb.vh).
`timescale 1ns/1ps
`include "params.vh"
module tb_dof_row_mac;
    `include "hs_tb.vh"
    localparam T = 2 * `P_HALF + 1;
    localparam HX = `P_HX_BITS;
    localparam HA = `P_HA_BITS;
    localparam VX = `P_VX_BITS;
    localparam VA = `P_VA_BITS;
    localparam E = 4 + 3 * T;
    reg [63:0] e_sx, e_ovf, e_sa, e_sd, e_w;
    reg [`P_LAYER_BITS-1:0] layer;
    reg [`P_POS_BITS-1:0] pos, len;
    reg [T*HX-1:0] h_x;
    reg [T*HA-1:0] h_a, h_d;
    reg [T*VX-1:0] v_x;
    reg [T*VA-1:0] v_a, v_d;
    wire [`P_H_OUT_BITS-1:0] h_sx;
    wire [`P_H_SA_BITS-1:0] h_sa, h_sd;
    wire [`P_V_OUT_BITS-1:0] v_sx;
    wire [`P_V_SA_BITS-1:0] v_sa, v_sd;
    wire [`P_C_BITS-1:0] h_w, v_w;
    wire h_ovf, v_ovf;
    integer j, base;
    dof_row_mac #(.HALF(`P_HALF), .LAYERS(`P_LAYERS), .LAYER_BITS(`P_LAYER_BITS),
                  .C_BITS(`P_C_BITS), .POS_BITS(`P_POS_BITS),
                  .HX_BITS(HX), .HA_BITS(HA), .H_OUT_BITS(`P_H_OUT_BITS), .H_SA_BITS(`P_H_SA_BITS),
                  .VX_BITS(VX), .VA_BITS(VA), .V_OUT_BITS(`P_V_OUT_BITS), .V_SA_BITS(`P_V_SA_BITS))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
             .out_valid(out_valid), .out_ready(out_ready),
             .h_layer(layer), .h_pos(pos), .h_len(len), .h_x(h_x), .h_a(h_a), .h_d(h_d),
             .h_sx(h_sx), .h_ovf(h_ovf), .h_sa(h_sa), .h_sd(h_sd), .h_w(h_w),
             .v_layer(layer), .v_pos(pos), .v_len(len), .v_x(v_x), .v_a(v_a), .v_d(v_d),
             .v_sx(v_sx), .v_ovf(v_ovf), .v_sa(v_sa), .v_sd(v_sd), .v_w(v_w));
    task drive(input integer k);
        begin
            base = k * `N_FIELDS;
            layer = mem[base + 1];
            pos = mem[base + 2];
            len = mem[base + 3];
            for (j = 0; j < T; j = j + 1) begin
                h_x[j*HX +: HX] = mem[base + 4 + j];
                v_x[j*VX +: VX] = mem[base + 4 + j];
                h_a[j*HA +: HA] = mem[base + 4 + T + j];
                v_a[j*VA +: VA] = mem[base + 4 + T + j];
                h_d[j*HA +: HA] = mem[base + 4 + 2 * T + j];
                v_d[j*VA +: VA] = mem[base + 4 + 2 * T + j];
            end
        end
    endtask
    task check(input integer k, output reg bad_k);
        begin
            base = k * `N_FIELDS;
            e_sx = mem[base + E];
            e_ovf = mem[base + E + 1];
            e_sa = mem[base + E + 2];
            e_sd = mem[base + E + 3];
            e_w = mem[base + E + 4];
            if (mem[base] == 0)
                bad_k = h_sx !== e_sx[`P_H_OUT_BITS-1:0] || e_sx >> `P_H_OUT_BITS != 0
                   || h_ovf !== e_ovf[0] || e_ovf > 1
                   || h_sa !== e_sa[`P_H_SA_BITS-1:0] || e_sa >> `P_H_SA_BITS != 0
                   || h_sd !== e_sd[`P_H_SA_BITS-1:0] || e_sd >> `P_H_SA_BITS != 0
                   || h_w !== e_w[`P_C_BITS-1:0] || e_w >> `P_C_BITS != 0;
            else
                bad_k = mem[base] != 1
                   || v_sx !== e_sx[`P_V_OUT_BITS-1:0] || e_sx >> `P_V_OUT_BITS != 0
                   || v_ovf !== e_ovf[0] || e_ovf > 1
                   || v_sa !== e_sa[`P_V_SA_BITS-1:0] || e_sa >> `P_V_SA_BITS != 0
                   || v_sd !== e_sd[`P_V_SA_BITS-1:0] || e_sd >> `P_V_SA_BITS != 0
                   || v_w !== e_w[`P_C_BITS-1:0] || e_w >> `P_C_BITS != 0;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (pass=%0h layer=%0h pos=%0h len=%0h expected sx=%0h ovf=%0h sa=%0h sd=%0h w=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1],
                 mem[first*`N_FIELDS+2], mem[first*`N_FIELDS+3], mem[first*`N_FIELDS+E],
                 mem[first*`N_FIELDS+E+1], mem[first*`N_FIELDS+E+2], mem[first*`N_FIELDS+E+3],
                 mem[first*`N_FIELDS+E+4]);
    endtask
endmodule
