// Self-checking testbench of acc_mac: fields per vector: w, i, acc_in, expected acc_out,
// expected ovf, expected clamp_out, expected clamp_ovf (two's complement words for a signed
// kernel, masked to their widths). The vectors stream through the handshake (hs_tb.vh).
`timescale 1ns/1ps
`include "params.vh"
module tb_acc_mac;
    `include "hs_tb.vh"
    reg [63:0] e, eo, ec, eco;
    reg [`P_W_BITS-1:0] w;
    reg [`P_I_BITS-1:0] i;
    reg [`P_A_BITS-1:0] acc_in;
    wire [`P_A_BITS-1:0] acc_out;
    wire [`P_F_BITS-1:0] clamp_out;
    wire ovf, clamp_ovf;
    acc_mac #(.W_BITS(`P_W_BITS), .I_BITS(`P_I_BITS), .F_BITS(`P_F_BITS), .SHIFT(`P_SHIFT),
              .QUANT(`P_QUANT), .OVF(`P_OVF), .SIGNED(`P_SIGNED), .A_BITS(`P_A_BITS))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready),
             .out_valid(out_valid), .out_ready(out_ready), .w(w), .i(i), .acc_in(acc_in),
             .acc_out(acc_out), .ovf(ovf), .clamp_out(clamp_out), .clamp_ovf(clamp_ovf));
    task drive(input integer k);
        begin
            w = mem[k*`N_FIELDS];
            i = mem[k*`N_FIELDS+1];
            acc_in = mem[k*`N_FIELDS+2];
        end
    endtask
    task check(input integer k, output reg bad_k);
        begin
            e = mem[k*`N_FIELDS+3];
            eo = mem[k*`N_FIELDS+4];
            ec = mem[k*`N_FIELDS+5];
            eco = mem[k*`N_FIELDS+6];
            bad_k = acc_out !== e[`P_A_BITS-1:0] || e >> `P_A_BITS != 0 || ovf !== eo[0] || eo > 1
                || clamp_out !== ec[`P_F_BITS-1:0] || ec >> `P_F_BITS != 0
                || clamp_ovf !== eco[0] || eco > 1;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (w=%0h i=%0h acc_in=%0h expected acc_out=%0h ovf=%0h clamp_out=%0h clamp_ovf=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1],
                 mem[first*`N_FIELDS+2], mem[first*`N_FIELDS+3], mem[first*`N_FIELDS+4],
                 mem[first*`N_FIELDS+5], mem[first*`N_FIELDS+6]);
    endtask
endmodule
