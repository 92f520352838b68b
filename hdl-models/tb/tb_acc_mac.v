// Self-checking testbench of acc_mac: fields per vector: w, i, acc_in, expected acc_out,
// expected ovf, expected clamp_out, expected clamp_ovf (two's complement words for a signed
// kernel, masked to their widths).
`timescale 1ns/1ps
`include "params.vh"
module tb_acc_mac;
    reg clk = 0;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [63:0] e, eo, ec, eco;
    reg [`P_W_BITS-1:0] w;
    reg [`P_I_BITS-1:0] i;
    reg [`P_A_BITS-1:0] acc_in;
    wire [`P_A_BITS-1:0] acc_out;
    wire [`P_F_BITS-1:0] clamp_out;
    wire ovf, clamp_ovf;
    integer k, errors, first;
    acc_mac #(.W_BITS(`P_W_BITS), .I_BITS(`P_I_BITS), .F_BITS(`P_F_BITS), .SHIFT(`P_SHIFT),
              .QUANT(`P_QUANT), .OVF(`P_OVF), .SIGNED(`P_SIGNED), .A_BITS(`P_A_BITS))
        dut (.clk(clk), .w(w), .i(i), .acc_in(acc_in), .acc_out(acc_out), .ovf(ovf),
             .clamp_out(clamp_out), .clamp_ovf(clamp_ovf));
    initial begin
        $readmemh("vectors.hex", mem);
        errors = 0;
        first = -1;
        for (k = 0; k < `N_VECTORS; k = k + 1) begin
            w = mem[k*`N_FIELDS];
            i = mem[k*`N_FIELDS+1];
            acc_in = mem[k*`N_FIELDS+2];
            #1 clk = 1;
            #1 clk = 0;
            e = mem[k*`N_FIELDS+3];
            eo = mem[k*`N_FIELDS+4];
            ec = mem[k*`N_FIELDS+5];
            eco = mem[k*`N_FIELDS+6];
            if (acc_out !== e[`P_A_BITS-1:0] || e >> `P_A_BITS != 0 || ovf !== eo[0] || eo > 1
                || clamp_out !== ec[`P_F_BITS-1:0] || ec >> `P_F_BITS != 0
                || clamp_ovf !== eco[0] || eco > 1) begin
                if (errors == 0) first = k;
                errors = errors + 1;
            end
        end
        if (errors == 0) $display("TESTBENCH OK %0d vectors", `N_VECTORS);
        else $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (w=%0h i=%0h acc_in=%0h expected acc_out=%0h ovf=%0h clamp_out=%0h clamp_ovf=%0h)",
                      errors, `N_VECTORS, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1],
                      mem[first*`N_FIELDS+2], mem[first*`N_FIELDS+3], mem[first*`N_FIELDS+4],
                      mem[first*`N_FIELDS+5], mem[first*`N_FIELDS+6]);
        $finish;
    end
endmodule
