// Self-checking testbench of gamma_lut: fields per vector: acc, expected dac.
`timescale 1ns/1ps
`include "params.vh"
module tb_gamma_lut;
    reg clk = 0;
    reg [63:0] mem [0:`N_VECTORS*`N_FIELDS-1];
    reg [63:0] e;
    reg [`P_ACC_BITS-1:0] acc;
    wire [`P_DAC_BITS-1:0] dac;
    integer k, errors, first;
    gamma_lut #(.ACC_BITS(`P_ACC_BITS), .FRAC_BITS(`P_FRAC_BITS), .DAC_BITS(`P_DAC_BITS),
                .ROM_FILE("gamma_rom.hex")) dut (.clk(clk), .acc(acc), .dac(dac));
    initial begin
        $readmemh("vectors.hex", mem);
        errors = 0;
        first = -1;
        for (k = 0; k < `N_VECTORS; k = k + 1) begin
            acc = mem[k*`N_FIELDS];
            #1 clk = 1;
            #1 clk = 0;
            e = mem[k*`N_FIELDS+1];
            if (dac !== e[`P_DAC_BITS-1:0] || e >> `P_DAC_BITS != 0) begin
                if (errors == 0) first = k;
                errors = errors + 1;
            end
        end
        if (errors == 0) $display("TESTBENCH OK %0d vectors", `N_VECTORS);
        else $display("TESTBENCH FAILED: %0d of %0d vectors differ, first vector %0d (acc=%0h expected dac=%0h)",
                      errors, `N_VECTORS, first, mem[first*`N_FIELDS], mem[first*`N_FIELDS+1]);
        $finish;
    end
endmodule
