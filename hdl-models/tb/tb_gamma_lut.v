// Self-checking testbench of gamma_lut: fields per vector: acc, expected dac. The vectors
// stream through the handshake (hs_tb.vh).
`timescale 1ns/1ps
`include "params.vh"
module tb_gamma_lut;
    `include "hs_tb.vh"
    reg [63:0] e;
    reg [`P_ACC_BITS-1:0] acc;
    wire [`P_DAC_BITS-1:0] dac;
    gamma_lut #(.ACC_BITS(`P_ACC_BITS), .FRAC_BITS(`P_FRAC_BITS), .DAC_BITS(`P_DAC_BITS),
                .ROM_FILE("gamma_rom.hex"))
        dut (.clk(clk), .rst(rst), .in_valid(in_valid), .in_ready(in_ready), .acc(acc),
             .out_valid(out_valid), .out_ready(out_ready), .dac(dac));
    task drive(input integer k);
        acc = mem[k*`N_FIELDS];
    endtask
    task check(input integer k, output reg bad_k);
        begin
            e = mem[k*`N_FIELDS+1];
            bad_k = dac !== e[`P_DAC_BITS-1:0] || e >> `P_DAC_BITS != 0;
        end
    endtask
    task fail_line;
        $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (acc=%0h expected dac=%0h)",
                 errors, total, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1]);
    endtask
endmodule
